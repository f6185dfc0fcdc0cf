/* SPDX-License-Identifier: Apache-2.0 */
/** @file
 * libflatline - the quality record: recordings of a gauge's input, and the
 * archive of every measured sheet.
 *
 * What it does
 *   A recording (flt_recorder to write, flt_recording to read) keeps what
 *   a gauge measured as it ran: every profile row it took (per fiber the
 *   height each laser saw, quantized, and whether the fiber was valid, off
 *   the strip or not measured), the encoder position and time of each,
 *   the strip's edges and saturated peaks per row, what happened before
 *   each row (frames skipped at a line stop or reversal, dropped at a full
 *   queue, missing from the encoder's count, a new strip), the cuts, the
 *   coils' identities, the calibration and the gauge's options; raw camera
 *   frames on request (all, or the last seconds kept in memory and saved
 *   when asked or when a sheet fails). Replayed through a gauge
 *   (flt_source_open_recording, flatline/source.h) with the same options
 *   it gives the same sheets bit for bit; with other options it answers
 *   "what if". docs/record.md documents the file format (an SQLite
 *   database, readable without libflatline from Python's standard library
 *   and numpy, or from C# through Microsoft.Data.Sqlite).
 *
 *   An archive (flt_archive) keeps every finished sheet: its results, its
 *   verdict, its counters, its coil's identity and statistics, and its
 *   reconstructed height map (quantized and compressed), indexed by coil
 *   and time, with retention limits (days, bytes). It is an SQLite file by
 *   default (embedded, no server), or the same tables on a PostgreSQL
 *   server (libpq, loaded when the archive is opened: "libpq.so.5" on
 *   Linux, "libpq.dll" on Windows, or the file named by the environment
 *   variable FLT_LIBPQ), where several lines share one quality database.
 *
 * Quantization
 *   While a recorder is attached, the gauge measures the rows it records:
 *   each laser's height at each fiber is rounded to the recording's
 *   quantum (option record_quantum, a power of two, default 2^-8 mm =
 *   0.0039 mm: an error of at most 0.002 mm, 2 % of the reference sensor's
 *   noise) before the reconstructor takes it, so that a replay is exact.
 *   docs/record.md gives the measured cost per sample.
 *
 * Crash safety
 *   The recorder's writer thread commits at least every
 *   record_commit_interval ms (default 250); with record_sync = 1 (the
 *   default) each commit reaches the disk before the next begins. A
 *   process that is killed, or a computer that loses power, leaves a file
 *   that opens and holds every row up to the last commit: at most
 *   2 x record_commit_interval + the commit itself before the end (the
 *   test kills the writer 20 times: every row older than 1 s is there).
 *   Every block of rows carries a CRC-32 of its stored bytes
 *   (flt_recording_verify).
 *
 * Nothing lost without a word
 *   Neither the recorder nor the archive ever makes the gauge wait for a
 *   disk or a server. The recorder queues up to record_queue_blocks blocks
 *   for its writer; beyond that, rows are not recorded, counted
 *   (FLT_RECORDER_COUNT_ROWS_LOST) and the gap is marked in the file. The
 *   archive keeps sheets it could not store (a server that restarts, a
 *   full disk) in memory, up to archive_buffer_mb, retries every
 *   archive_retry_interval ms, and counts and logs what it could not keep.
 *
 * Threads
 *   A recorder or an archive may be used from any thread (each has a
 *   mutex); their writer threads start when they are opened.
 *   A flt_recording is read by one thread at a time.
 *
 * Memory
 *   flt_recorder_create() allocates the block buffers: (record_queue_blocks
 *   + 2) x record_block_rows x (9 K + 58) bytes for K fibers (49 MB at
 *   the defaults and 1,150 fibers), and 1.5 MB for SQLite's connection and
 *   page cache (tests/c/test_memory.c checks it, docs/memory.md); the
 *   frame ring (record_frames = "ring") fills up to record_frame_mb as
 *   frames come. Rows and cuts allocate nothing after that; the writer
 *   thread's encoding scratch grows to its largest block once. The
 *   archive allocates a copy of each sheet it stores (freed once
 *   stored), bounded by archive_buffer_mb.
 */
#ifndef FLATLINE_RECORD_H
#define FLATLINE_RECORD_H

#include "flatline/calib.h"
#include "flatline/coil.h"
#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A recording being written (opaque handle). */
typedef struct flt_recorder flt_recorder;
/** A recording opened for reading (opaque handle). */
typedef struct flt_recording flt_recording;
/** An archive of measured sheets (opaque handle). */
typedef struct flt_archive flt_archive;

/** The format version this library writes (docs/record.md); it reads this
 * one and the ones before it. */
#define FLT_RECORDING_VERSION 1
/** The archive schema version this library writes and reads. */
#define FLT_ARCHIVE_VERSION   1

/* ---------------------------------------------------------------------- */
/* Writing a recording                                                     */
/* ---------------------------------------------------------------------- */

/** Values of the option "record_frames" (FLT_OPT_RECORD_FRAMES): which raw
 * camera frames a recorder attached to a gauge keeps. */
typedef enum flt_record_frames {
    /** "none": profile rows only (the default). */
    FLT_RECORD_FRAMES_NONE = 0,
    /** "all": every frame the gauge takes (for slow lines and short
     * recordings: a 2048 x 256 Mono8 frame is 512 KiB before compression). */
    FLT_RECORD_FRAMES_ALL = 1,
    /** "ring": the last record_frame_seconds of frames, kept in memory
     * (record_frame_mb at most) and written by flt_recorder_save_frames()
     * or, with record_frames_on_fail, when a sheet fails its rules. */
    FLT_RECORD_FRAMES_RING = 2,
    FLT_RECORD_FRAMES_MAX_ENUM_ = 0x7FFFFFFF
} flt_record_frames;

/** Creates a recording file and starts its writer thread.
 * @param path    the file to create (UTF-8); an existing file is refused
 *                (a record is never overwritten by mistake).
 * @param calib   the sensor's finished calibration (stored in the file;
 *                its fiber count is the rows').
 * @param options NULL, or the record_* keys.
 * @param out     receives the recorder; NULL on failure.
 * @return FLT_OK; FLT_ERR_IO when the file exists or cannot be created;
 *         FLT_ERR_STATE for an unfinished calibration;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument or an option of
 *         another component; FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recorder_create(const char *path,
                                                              const flt_calib *calib,
                                                              const flt_options *options,
                                                              flt_recorder **out);

/** Writes what is buffered, stops the writer thread and closes the file
 * (a gauge it is attached to must have detached it first: see
 * flt_gauge_attach_recorder). NULL is a no-op.
 * @param recorder the recorder, or NULL.
 */
FLT_API void FLT_CALL flt_recorder_destroy(flt_recorder *recorder);

/** Records one profile row (for a sensor that extracts its own profiles,
 * or any program that makes rows): as flt_gauge_push_row() takes it, at
 * the host's time now. A gauge with this recorder attached records its
 * own rows: do not call this then (FLT_ERR_STATE).
 * @param recorder   the recorder.
 * @param encoder_mm the row's encoder position, mm (finite, |e| <= 1e12).
 * @param fibers     must equal the calibration's fiber count.
 * @param height     [fibers] mm (NaN where not measured).
 * @param slope      [fibers] mm/mm (NaN where not measured).
 * @param valid      [fibers] non-zero where valid, or NULL (finite values
 *                   are valid).
 * @return FLT_OK (also when the row could not be queued: then
 *         FLT_RECORDER_COUNT_ROWS_LOST counts it); FLT_ERR_INVALID_ARGUMENT
 *         for a NULL or wrong argument; FLT_ERR_STATE while a gauge
 *         records through it; the writer's failure (FLT_ERR_IO: a full
 *         disk) once it stopped.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recorder_push_row(flt_recorder *recorder,
                                                                double encoder_mm, size_t fibers,
                                                                const double *height,
                                                                const double *slope,
                                                                const uint8_t *valid);

/** Records a cut of the shear at encoder_mm (as flt_gauge_cut), before the
 * next row. FLT_ERR_STATE while a gauge records through the recorder.
 * @param recorder   the recorder.
 * @param encoder_mm where the shear cut, mm (finite, |e| <= 1e12).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT; FLT_ERR_STATE as above.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recorder_cut(flt_recorder *recorder,
                                                           double encoder_mm);

/** Records a coil's identity (as flt_gauge_set_coil), before the next
 * row. FLT_ERR_STATE while a gauge records through the recorder.
 * @param recorder the recorder.
 * @param coil     the identity (copied).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT; FLT_ERR_STATE as above.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recorder_set_coil(flt_recorder *recorder,
                                                                const flt_coil_info *coil);

/** Waits until everything given so far is committed to the file.
 * @param recorder   the recorder.
 * @param timeout_ms the longest wait, ms.
 * @return FLT_OK; FLT_ERR_TIMEOUT; the writer's failure (FLT_ERR_IO).
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recorder_sync(flt_recorder *recorder,
                                                            uint32_t timeout_ms);

/** Writes the frames kept in the ring (record_frames = "ring") to the
 * file now; the ring then starts empty.
 * @param recorder the recorder.
 * @return FLT_OK (nothing to do without a ring); FLT_ERR_INVALID_ARGUMENT
 *         for a NULL recorder.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recorder_save_frames(flt_recorder *recorder);

/** Recorder counters, since it was created (flt_recorder_count()). */
typedef enum flt_recorder_counter {
    FLT_RECORDER_COUNT_ROWS = 0,        /**< rows given to the recorder */
    FLT_RECORDER_COUNT_ROWS_STORED = 1, /**< rows committed to the file */
    /** Rows not recorded: the writer was behind by record_queue_blocks
     * blocks, or had failed (each such gap is marked in the file). */
    FLT_RECORDER_COUNT_ROWS_LOST = 2,
    FLT_RECORDER_COUNT_BLOCKS = 3,      /**< blocks committed */
    FLT_RECORDER_COUNT_COMMITS = 4,     /**< transactions committed */
    FLT_RECORDER_COUNT_BYTES = 5,       /**< bytes of row data stored (compressed) */
    FLT_RECORDER_COUNT_SAMPLES = 6,     /**< samples stored (rows x fibers) */
    FLT_RECORDER_COUNT_FRAMES = 7,      /**< raw frames written */
    FLT_RECORDER_COUNT_FRAMES_LOST = 8, /**< raw frames not written (ring or writer full) */
    FLT_RECORDER_COUNT_EVENTS = 9,      /**< cuts, coils and other events recorded */
    /** Nanoseconds the writer thread spent encoding and writing. */
    FLT_RECORDER_COUNT_WRITER_NS = 10,
    FLT_RECORDER_COUNTER_MAX_ENUM_ = 0x7FFFFFFF
} flt_recorder_counter;

/** A counter (flt_recorder_counter).
 * @param recorder the recorder.
 * @param counter  which counter.
 * @param out      receives its value.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument or an
 *         unknown counter.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recorder_count(const flt_recorder *recorder,
                                                             flt_recorder_counter counter,
                                                             uint64_t *out);

/* ---------------------------------------------------------------------- */
/* Reading a recording                                                     */
/* ---------------------------------------------------------------------- */

/** Opens a recording for reading (also one still being written, or one
 * whose writer was killed: it holds what was committed).
 * @param path the file (UTF-8).
 * @param out  receives the handle; NULL on failure.
 * @return FLT_OK; FLT_ERR_IO when the file cannot be opened;
 *         FLT_ERR_FORMAT when it is no recording or of a later version
 *         (the message says which); FLT_ERR_INVALID_ARGUMENT for a NULL
 *         argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recording_open(const char *path, flt_recording **out);

/** Closes a recording. NULL is a no-op.
 * @param recording the recording, or NULL.
 */
FLT_API void FLT_CALL flt_recording_destroy(flt_recording *recording);

/** What flt_recording_info() tells about a recording. */
typedef enum flt_recording_value {
    FLT_RECORDING_VERSION_OF = 0, /**< its format version */
    FLT_RECORDING_FIBERS = 1,     /**< fibers per row */
    FLT_RECORDING_ROWS = 2,       /**< rows stored */
    FLT_RECORDING_BLOCKS = 3,     /**< blocks stored */
    FLT_RECORDING_FRAMES = 4,     /**< raw frames stored */
    FLT_RECORDING_EVENTS = 5,     /**< events (cuts, coils, ...) stored */
    FLT_RECORDING_QUANTUM = 6,    /**< the height quantum, mm */
    /** The host's UTC time of the first and the last row, s since
     * 1970-01-01 (NaN without rows). */
    FLT_RECORDING_FIRST_TIME = 7,
    FLT_RECORDING_LAST_TIME = 8, /**< time of the last row, s (UTC) */
    /** Encoder position of the first and the last row, mm. */
    FLT_RECORDING_FIRST_ENCODER = 9,
    FLT_RECORDING_LAST_ENCODER = 10, /**< encoder of the last row, mm */
    FLT_RECORDING_ROWS_LOST = 11,    /**< rows the writer marked as lost */
    FLT_RECORDING_BYTES = 12,        /**< bytes of the rows' blocks */
    /** 1 when the gauge's options were recorded (flt_recording_options). */
    FLT_RECORDING_HAS_OPTIONS = 13,
    FLT_RECORDING_VALUE_MAX_ENUM_ = 0x7FFFFFFF
} flt_recording_value;

/** One value about the recording (flt_recording_value).
 * @param recording the recording.
 * @param key       which value.
 * @param out       receives it.
 * @return FLT_OK; FLT_ERR_NOT_FOUND for an unknown key;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recording_info(const flt_recording *recording,
                                                             flt_recording_value key, double *out);

/** The calibration the recording was made with (a new handle).
 * @param recording the recording.
 * @param out       receives the calibration (flt_calib_destroy).
 * @return FLT_OK; FLT_ERR_FORMAT when the stored calibration is damaged;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recording_calib(const flt_recording *recording,
                                                              flt_calib **out);

/** The options of the gauge that made the recording (a new bag): the same
 * options give the same sheets. Every default when no gauge options were
 * recorded (FLT_RECORDING_HAS_OPTIONS = 0).
 * @param recording the recording.
 * @param out       receives the bag (flt_options_destroy).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recording_options(const flt_recording *recording,
                                                                flt_options **out);

/** Checks every block: its CRC-32 and that it decodes.
 * @param recording      the recording.
 * @param bad_blocks_out receives how many blocks failed (0: all good).
 * @return FLT_OK when every block is good; FLT_ERR_FORMAT naming the first
 *         bad block otherwise (bad_blocks_out is set either way);
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recording_verify(const flt_recording *recording,
                                                               uint64_t *bad_blocks_out);

/** Reads rows [first, first + count) (clipped at the last row), as the
 * gauge measured them. Any output may be NULL.
 * @param recording      the recording.
 * @param first          the first row, 0 ..
 * @param count          rows wanted (the arrays' rows).
 * @param fibers         must equal FLT_RECORDING_FIBERS.
 * @param encoder_mm_out [count] encoder positions, mm.
 * @param time_s_out     [count] host UTC times, s since 1970.
 * @param height_out     [count * fibers] heights, mm (NaN where the
 *                       sample is not valid).
 * @param slope_out      [count * fibers] slopes, mm/mm (NaN likewise).
 * @param flags_out      [count * fibers] 0 for a valid sample, else the
 *                       reconstructor's FLT_FLAG_INVALID_INPUT or
 *                       FLT_FLAG_OFF_STRIP (flatline/recon.h).
 * @param rows_out       receives the rows read (0 past the end).
 * @return FLT_OK; FLT_ERR_FORMAT for a damaged block (naming it);
 *         FLT_ERR_INVALID_ARGUMENT for a NULL recording or rows_out, or a
 *         wrong fiber count.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL
flt_recording_read_rows(const flt_recording *recording, uint64_t first, size_t count, size_t fibers,
                        double *encoder_mm_out, double *time_s_out, double *height_out,
                        double *slope_out, uint8_t *flags_out, size_t *rows_out);

/* ---------------------------------------------------------------------- */
/* The archive                                                             */
/* ---------------------------------------------------------------------- */

/** Opens (creating its tables if needed) an archive and starts its writer
 * thread.
 * @param location a file path (UTF-8) for SQLite; or a PostgreSQL
 *                 connection string: a URI ("postgresql://user@host/db")
 *                 or "pg:" followed by libpq's key=value form
 *                 ("pg:host=q1 dbname=quality").
 * @param line     the line's name, stored with every sheet (several lines
 *                 may share a PostgreSQL archive): text as in
 *                 flatline/coil.h, "" allowed.
 * @param options  NULL, or the archive_* keys.
 * @param out      receives the archive; NULL on failure.
 * @return FLT_OK; FLT_ERR_IO when the file or the server cannot be opened
 *         (with the server's words); FLT_ERR_FORMAT for a file that is
 *         no SQLite database, a database whose tables are no flatline
 *         archive, or an archive of another schema version; FLT_ERR_NOT_FOUND when libpq cannot be
 *         loaded (the message names the file tried);
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or malformed argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_archive_open(const char *location, const char *line,
                                                           const flt_options *options,
                                                           flt_archive **out);

/** Stores what is pending (waiting up to archive_close_timeout ms for the
 * database), stops the writer thread and closes the archive; sheets still
 * not stored then are counted lost and logged. A gauge it is attached to
 * must have detached it first. NULL is a no-op.
 * @param archive the archive, or NULL.
 */
FLT_API void FLT_CALL flt_archive_destroy(flt_archive *archive);

/** Waits until every sheet given so far is stored (or the timeout).
 * @param archive    the archive.
 * @param timeout_ms the longest wait, ms.
 * @return FLT_OK; FLT_ERR_TIMEOUT with the database's last error in the
 *         message; FLT_ERR_INVALID_ARGUMENT for a NULL archive.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_archive_flush(flt_archive *archive,
                                                            uint32_t timeout_ms);

/** Applies the retention limits now (the writer applies them after every
 * coil and at most every 64 sheets).
 * @param archive     the archive.
 * @param removed_out receives the sheets removed, or NULL.
 * @return FLT_OK; the database's error (FLT_ERR_IO);
 *         FLT_ERR_INVALID_ARGUMENT for a NULL archive.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_archive_prune(flt_archive *archive,
                                                            uint64_t *removed_out);

/** Archive counters, since it was opened (flt_archive_count()). */
typedef enum flt_archive_counter {
    FLT_ARCHIVE_COUNT_SHEETS = 0,  /**< sheets given to the archive */
    FLT_ARCHIVE_COUNT_STORED = 1,  /**< sheets stored */
    FLT_ARCHIVE_COUNT_PENDING = 2, /**< sheets waiting to be stored now */
    /** Sheets not stored: the buffer (archive_buffer_mb) was full while
     * the database was away, or it was still away at close. */
    FLT_ARCHIVE_COUNT_LOST = 3,
    FLT_ARCHIVE_COUNT_FAILURES = 4,      /**< store attempts that failed */
    FLT_ARCHIVE_COUNT_RECONNECTS = 5,    /**< connections made again (PostgreSQL) */
    FLT_ARCHIVE_COUNT_PRUNED = 6,        /**< sheets removed by the retention limits */
    FLT_ARCHIVE_COUNT_BYTES = 7,         /**< bytes of sheet data stored */
    FLT_ARCHIVE_COUNT_PENDING_BYTES = 8, /**< bytes waiting to be stored */
    FLT_ARCHIVE_COUNTER_MAX_ENUM_ = 0x7FFFFFFF
} flt_archive_counter;

/** A counter (flt_archive_counter).
 * @param archive the archive.
 * @param counter which counter.
 * @param out     receives its value.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument or an
 *         unknown counter.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_archive_count(const flt_archive *archive,
                                                            flt_archive_counter counter,
                                                            uint64_t *out);

/** The archive's backend: 0 SQLite, 1 PostgreSQL.
 * @param archive the archive.
 * @param out     receives 0 or 1.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_archive_backend(const flt_archive *archive, int *out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_RECORD_H */
