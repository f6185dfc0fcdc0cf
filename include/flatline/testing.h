// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline testing tier - test doubles for acquisition without hardware:
 * a simulated USB bus with simulated USB3 Vision cameras, fault injection,
 * and a look at the camera's registers from outside; and a hidden leveler
 * for the advisor's closed loop (flt_leveler_sim, at the end).
 *
 * What       A simulated USB bus behind the same transport seam as libusb:
 *            the real client code of libflatline (discovery, GenCP,
 *            bootstrap, GenICam features, stream set-up, frame assembly)
 *            talks to it. Each camera has the U3V descriptors, a register
 *            map answering GenCP (ABRM, SBRM, SIRM, the feature registers),
 *            a manifest with its GenICam XML (zipped or not) and a stream of
 *            leader, payload and trailer transfers with USB packet semantics
 *            (512-byte packets, a short packet ends a transfer, a packet
 *            larger than the space left overflows). The bus also holds one
 *            device that is not a camera. Time is virtual: a simulated
 *            timeout returns at once.
 *
 * Tier       This header belongs to a separate library, libflatline_testing
 *            (CMake: find_package(flatline COMPONENTS testing), target
 *            flatline::testing; pkg-config: flatline-testing). It is NOT
 *            under libflatline's ABI promise: functions, enumerators and
 *            behaviour here may change in any release, like zstd's
 *            static-linking-only API or libgit2's sys/ headers. The library
 *            must come from the same release as the libflatline it is used
 *            with: its transports carry the release they were built for,
 *            and libflatline refuses any other (FLT_ERR_INVALID_ARGUMENT).
 *            Production programs link libflatline only.
 *
 * Using it   A bus gives its transport (flt_u3v_sim_transport()); pass it
 *            where flatline/source.h takes a flt_usb_transport:
 *
 *                flt_u3v_sim *bus;  flt_usb_transport *usb;  flt_source *src;
 *                flt_u3v_sim_create(&bus);
 *                flt_u3v_sim_add_camera(bus, "Vendor", "Model", "SN1", 2048, 256,
 *                                       FLT_PIXEL_MONO8, NULL);
 *                flt_u3v_sim_transport(bus, &usb);
 *                flt_source_open_u3v(usb, "SN1", NULL, &src);
 *                ...
 *                flt_source_destroy(src);
 *                flt_u3v_sim_destroy(bus);
 *
 * Errors     Every function returns a flt_status and sets the thread's last
 *            error (flt_last_error_message()) as libflatline's own do.
 *
 * Feature registers (Width at 0x10000, Height 0x10004, PixelFormat 0x10008,
 * OffsetY 0x1000C, AcquisitionMode 0x10010, AcquisitionStart 0x10014,
 * AcquisitionStop 0x10018, ExposureTimeRaw 0x1001C (us, integer),
 * TriggerSelector 0x10020, TriggerMode 0x10024, TriggerSource 0x10028,
 * Gain 0x1002C (float32)). SIRM is at 0x2000 (SI control at 0x2004). The XML
 * describes ExposureTime through a Converter of ExposureTimeRaw and
 * PayloadSize through an IntSwissKnife.
 *
 * Frames: without a simulator, byte i of the payload of block b is
 * (uint8_t)(b * 131 + i * 7 + (i >> 9)) (test pattern; 16-bit formats hold
 * the same bytes). With flt_u3v_sim_set_frames() the payload is the
 * simulator's rendered frame. With the encoder chunk on, the payload ends
 * with a chunk: the 64-bit little-endian encoder count, then the chunk id and
 * length (u32, little-endian each): count = round(encoder_mm /
 * encoder_mm_per_count), the simulator's position (else block * 3 mm).
 *
 * Memory     A bus owns its cameras; sources opened on it borrow it (destroy
 *            them first). The transport belongs to its bus.
 * Threads    A bus must not be used from two threads at once, nor while a
 *            source opened on it is used from another thread.
 */
#ifndef FLATLINE_TESTING_H
#define FLATLINE_TESTING_H

#include "flatline/common.h"
#include "flatline/sim.h"
#include "flatline/source.h"

/** @def FLT_TESTING_API
 * Marks the exported functions of libflatline_testing. */
#if defined(_WIN32) || defined(__CYGWIN__)
#  if defined(FLT_BUILDING_TESTING)
#    define FLT_TESTING_API __declspec(dllexport)
#  elif defined(FLT_STATIC)
#    define FLT_TESTING_API
#  else
#    define FLT_TESTING_API __declspec(dllimport)
#  endif
#else
#  if defined(__GNUC__) && __GNUC__ >= 4
#    define FLT_TESTING_API __attribute__((visibility("default")))
#  else
#    define FLT_TESTING_API
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/** A simulated USB bus with simulated USB3 Vision cameras. */
typedef struct flt_u3v_sim flt_u3v_sim;

/** Settings (before a camera is opened) and read-outs of a simulated camera. */
typedef enum flt_u3v_sim_param {
    FLT_U3V_SIM_RESPONSE_TIME_MS = 0,        /**< ABRM; default 200 */
    FLT_U3V_SIM_MAX_COMMAND_BYTES = 1,       /**< SBRM; default 1024 */
    FLT_U3V_SIM_MAX_ACK_BYTES = 2,           /**< SBRM; default 1024 */
    FLT_U3V_SIM_ALIGNMENT_LOG2 = 3,          /**< SIRM info; default 9 (512 B) */
    FLT_U3V_SIM_XML_ZIPPED = 4,              /**< default 1 */
    FLT_U3V_SIM_ENCODER_CHUNK = 5,           /**< 1: append the encoder chunk */
    FLT_U3V_SIM_ENCODER_CHUNK_ID = 6,        /**< default 0x4E434445 */
    FLT_U3V_SIM_ENCODER_MM_PER_COUNT_UM = 7, /**< um per count; default 10 */
    FLT_U3V_SIM_SPEED_MBPS = 8,              /**< default 5000 */
    /** 1: the camera was left streaming by a process that died: SI control
     * 1, acquisition running, a half-sent frame in its FIFO; SIRM writes
     * are refused (access denied) until SI control is cleared. */
    FLT_U3V_SIM_LEFT_STREAMING = 9,
    FLT_U3V_SIM_SI_CONTROL = 20,           /**< read-only: SIRM SI control register */
    FLT_U3V_SIM_ACQUIRING = 21,            /**< read-only: 1 between AcquisitionStart/Stop */
    FLT_U3V_SIM_COMMANDS = 22,             /**< read-only: GenCP commands received */
    FLT_U3V_SIM_LAST_READ_TIMEOUT_MS = 23, /**< read-only: timeout of the last control read */
    FLT_U3V_SIM_FRAMES_SENT = 24,          /**< read-only: leaders sent */
    FLT_U3V_SIM_OPEN = 25,                 /**< read-only: 1 while a host holds it open */
    /** read-only: control-channel and submit faults not yet applied in full
     * (stream faults are not counted) */
    FLT_U3V_SIM_FAULTS_PENDING = 26,
    FLT_U3V_SIM_UNPLUGGED = 27, /**< read-only: 1 once the camera was unplugged */
    FLT_U3V_SIM_PARAM_MAX_ENUM_ = 0x7FFFFFFF
} flt_u3v_sim_param;

/** Faults a simulated camera can be made to show (flt_u3v_sim_inject). */
typedef enum flt_u3v_fault {
    /* stream faults, applied to the frame with block id `at` */
    FLT_U3V_FAULT_SHORT_FRAME = 0,      /**< last payload transfer not sent */
    FLT_U3V_FAULT_LEADER_MID_FRAME = 1, /**< no trailer: next leader mid-frame */
    FLT_U3V_FAULT_OVERFLOW = 2,         /**< last transfer 1 packet too long */
    FLT_U3V_FAULT_SKIP_BLOCK_IDS = 3,   /**< `count` block ids from `at` are never sent */
    FLT_U3V_FAULT_STREAM_TIMEOUT = 4,   /**< the camera stalls after the leader */
    FLT_U3V_FAULT_UNPLUG = 5,           /**< unplugged after the leader */
    FLT_U3V_FAULT_GARBAGE = 6,          /**< 100 random bytes before the leader */
    FLT_U3V_FAULT_TRAILER_STATUS = 7,   /**< trailer status 0xA101 (overrun) */
    /* host faults: they hit the `count` operations (commands on the
     * control channel, or bulk submissions) that follow the next `at` ones
     * (`at` = 0: from the next one on); faults of one kind add up */
    FLT_U3V_FAULT_SUBMIT_REFUSED = 10,  /**< bulk submits refused (no memory) */
    FLT_U3V_FAULT_PENDING_ACK = 11,     /**< one command first gets `count` pending acks */
    FLT_U3V_FAULT_CONTROL_TIMEOUT = 12, /**< commands lost on the way: not executed, no answer */
    FLT_U3V_FAULT_LATE_ACK = 13, /**< one command's ack comes only after the following one's */
    FLT_U3V_FAULT_LOST_ACK = 14, /**< commands executed, their acks lost */
    FLT_U3V_FAULT_BUSY = 15,     /**< commands answered "busy" (0x8007), not executed */
    FLT_U3V_FAULT_CONTROL_UNPLUG = 16, /**< unplugged when one command arrives */
    FLT_U3V_FAULT_MAX_ENUM_ = 0x7FFFFFFF
} flt_u3v_fault;

/** An empty simulated bus (plus one device that is not a camera).
 * @param out the new bus (flt_u3v_sim_destroy()).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL `out`. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_u3v_sim_create(flt_u3v_sim **out);
/** Frees the bus. Sources opened on it must be destroyed first.
 * @param bus the bus; NULL is a no-op. */
FLT_TESTING_API void FLT_CALL flt_u3v_sim_destroy(flt_u3v_sim *bus);

/**
 * The bus as a USB transport, for flt_camera_list_create() and
 * flt_source_open_u3v() (flatline/source.h).
 * @param bus the bus.
 * @param out its transport, owned by the bus (valid until it is destroyed).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_u3v_sim_transport(flt_u3v_sim *bus,
                                                                        flt_usb_transport **out);

/**
 * Adds a camera (at most 8).
 * @param bus        the bus.
 * @param vendor     vendor name, copied, at most 63 bytes.
 * @param model      model name, copied, at most 63 bytes.
 * @param serial     serial number, copied, at most 63 bytes.
 * @param width      sensor width, 16..8192 px.
 * @param height     sensor height, 16..8192 px.
 * @param format     Mono8, 10, 12 or 16.
 * @param index_out  NULL, or the camera's index on the bus.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT naming a value out of range;
 *         FLT_ERR_BUFFER_FULL for a ninth camera.
 */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL
flt_u3v_sim_add_camera(flt_u3v_sim *bus, const char *vendor, const char *model, const char *serial,
                       uint32_t width, uint32_t height, flt_pixel_format format, size_t *index_out);

/** Renders the camera's frames with a simulator. The camera takes the
 * simulator's frame size and format.
 * @param bus     the bus.
 * @param camera  the camera's index.
 * @param sim     the simulator (borrowed: it must outlive its use by the
 *                camera); NULL: the test pattern.
 * @return FLT_OK; FLT_ERR_STATE while the camera is open;
 *         FLT_ERR_INVALID_ARGUMENT for a camera that does not exist. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_u3v_sim_set_frames(flt_u3v_sim *bus,
                                                                         size_t camera,
                                                                         flt_sim *sim);

/** Sets a parameter of a closed camera.
 * @param bus     the bus.
 * @param camera  the camera's index.
 * @param param   a settable flt_u3v_sim_param.
 * @param value   its value.
 * @return FLT_OK; FLT_ERR_STATE while the camera is open;
 *         FLT_ERR_INVALID_ARGUMENT for a value out of range or a read-only
 *         parameter. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_u3v_sim_set(flt_u3v_sim *bus, size_t camera,
                                                                  flt_u3v_sim_param param,
                                                                  uint64_t value);
/** A parameter or read-out of the camera.
 * @param bus     the bus.
 * @param camera  the camera's index.
 * @param param   any flt_u3v_sim_param.
 * @param out     its value.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a camera or parameter that
 *         does not exist. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_u3v_sim_get(const flt_u3v_sim *bus,
                                                                  size_t camera,
                                                                  flt_u3v_sim_param param,
                                                                  uint64_t *out);

/** Schedules a fault; faults add up.
 * @param bus     the bus.
 * @param camera  the camera's index.
 * @param fault   the fault (see flt_u3v_fault for what `at` and `count`
 *                mean for each).
 * @param at      stream faults: the block id; host faults: how many
 *                operations pass first.
 * @param count   how many frames, block ids or operations it hits.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for an unknown fault or camera. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_u3v_sim_inject(flt_u3v_sim *bus,
                                                                     size_t camera,
                                                                     flt_u3v_fault fault,
                                                                     uint64_t at, uint32_t count);

/** Reads a 32-bit little-endian register of the camera's map directly (no
 * GenCP): the camera's real state, whatever the host believes.
 * @param bus      the bus.
 * @param camera   the camera's index.
 * @param address  the register's byte address (its 4 bytes inside the map).
 * @param out      its value.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for an address outside the map or
 *         a camera that does not exist. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_u3v_sim_peek(const flt_u3v_sim *bus,
                                                                   size_t camera, uint64_t address,
                                                                   uint32_t *out);

/* ---------------------------------------------------------------------- */
/* A simulated leveler (for the advisor, flatline/advisor.h)               */
/* ---------------------------------------------------------------------- */

/** A hidden leveler: what flatline/advisor.h models, as a test double.
 *
 * Its true influence matrix G_true (zones x actuators, I-Units per unit)
 * maps the actuator settings u to the strip's zone elongation profile:
 *     e = incoming + G_true u + noise
 * (noise: N(0, noise_iu^2) per zone and sheet, drawn from (seed, sheet)).
 * Zone k spans x in [x0 + (k - 1/2) w, x0 + (k + 1/2) w] (x0 the centre of
 * zone 0, w the zone width, as flt_flatness_zone_layout() gives them).
 * Each sheet it produces is a height map for a flt_sim
 * (flt_sim_set_height_map()): fiber x of zone k carries a sine along
 * travel, z = A_k sin(2 pi (s - s0) / P), whose amplitude
 * A_k = (P / pi) sqrt(1e-5 (e_k - min e)) gives it e_k - min e I-Units,
 * so a gauge reading the sheet sees the elongation profile relative to its
 * shortest zone. The map has 8 columns per zone (the amplitude steps
 * between zones over one eighth of a zone) and 32 rows per period.
 *
 * Delay: settings given with flt_leveler_sim_set_settings() act on the
 * sheet after the next one produced (the next one is already in the
 * leveler while the gauge measures the last one): the leveler is one
 * sheet ahead of the gauge. The settings start at 0. */
typedef struct flt_leveler_sim flt_leveler_sim;

/** A hidden leveler.
 * @param zones          1 .. 1024.
 * @param actuators      1 .. 64.
 * @param zone_x0_mm     the centre of zone 0, mm (finite).
 * @param zone_width_mm  the zone width, mm (> 0).
 * @param g_true         [zones * actuators] row-major, I-Units per unit; copied.
 * @param g_count        zones * actuators.
 * @param incoming       [zones] the strip's elongation with every setting at
 *                       0, I-Units; copied.
 * @param incoming_count zones.
 * @param noise_iu       sheet-to-sheet noise per zone, I-Units (>= 0).
 * @param seed           the noise's seed.
 * @param out            the new leveler (flt_leveler_sim_destroy()).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT naming the argument. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_leveler_sim_create(
    size_t zones, size_t actuators, double zone_x0_mm, double zone_width_mm, const double *g_true,
    size_t g_count, const double *incoming, size_t incoming_count, double noise_iu, uint64_t seed,
    flt_leveler_sim **out);

/** Frees the leveler.
 * @param leveler the leveler; NULL is a no-op. */
FLT_TESTING_API void FLT_CALL flt_leveler_sim_destroy(flt_leveler_sim *leveler);

/** New settings; they act from the sheet after the next one on.
 * @param leveler        the leveler.
 * @param settings       [actuators] finite.
 * @param settings_count actuators.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_leveler_sim_set_settings(
    flt_leveler_sim *leveler, const double *settings, size_t settings_count);

/** A new coil: the strip's elongation with every setting at 0 from the
 * next sheet on (the settings and the delay are kept).
 * @param leveler        the leveler.
 * @param incoming       [zones] I-Units, finite; copied.
 * @param incoming_count zones.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_leveler_sim_set_incoming(
    flt_leveler_sim *leveler, const double *incoming, size_t incoming_count);

/** Levels the next sheet and puts it on the simulator: the sheet covers
 * s in [s0_mm, s0_mm + length_mm] (the simulator's defects are kept; its
 * height map is replaced).
 * @param leveler          the leveler.
 * @param sim              the simulator whose sheet it sets.
 * @param s0_mm            where the sheet starts along travel, mm.
 * @param length_mm        its length, mm (> 0, at most 1e6).
 * @param period_mm        the period of its waves, mm (length / 1000 ..
 *                         length).
 * @param elongation_out   [zones] receives e - min e, I-Units (what a
 *                         perfect gauge reads), or NULL.
 * @param elongation_count zones (0 with NULL).
 * @param settings_out     [actuators] receives the settings this sheet
 *                         went through, or NULL.
 * @param settings_count   actuators (0 with NULL).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT; what flt_sim_set_height_map()
 *         returns. */
FLT_TESTING_API FLT_NODISCARD flt_status FLT_CALL flt_leveler_sim_next_sheet(
    flt_leveler_sim *leveler, flt_sim *sim, double s0_mm, double length_mm, double period_mm,
    double *elongation_out, size_t elongation_count, double *settings_out, size_t settings_count);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_TESTING_H */
