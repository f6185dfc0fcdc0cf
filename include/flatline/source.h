// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - frame sources: a USB3 Vision camera (over libusb-1.0) or a
 * GigE Vision camera (over UDP), no camera SDK, recorded image sequences
 * and the simulator, behind one handle.
 *
 * A sensor is a camera plus an encoder. Every frame a source delivers carries
 * its pixels, pixel format, size, stride, block id, timestamp and the encoder
 * position of the strip when it was taken, so the same acquisition loop runs
 * on a line, on recorded images and on the simulator:
 *
 *     flt_source *src;  const flt_frame *frame;
 *     flt_source_open_u3v(NULL, NULL, options, &src);   (or _create_sim/_images)
 *     flt_source_start(src);
 *     while (flt_source_next(src, 1000, &frame) == FLT_OK && frame) {
 *         const void *pixels; uint32_t w, h; size_t stride; ...
 *         flt_frame_info(frame, &pixels, &w, &h, &stride, &format,
 *                        &block_id, &timestamp_ns, &encoder_mm);
 *         flt_extractor_process(ex, pixels, format, w, h, stride, encoder_mm, ...);
 *     }
 *     flt_source_destroy(src);          (stops the camera cleanly)
 *
 * Frame memory and lifetime
 *   Frames live in buffers the source allocates when it is created or
 *   started; nothing is allocated per frame (except inside OpenCV's image
 *   decoder for image sequences, an offline path). The frame returned by
 *   flt_source_next() is borrowed: it stays valid and unchanged until the
 *   next call of flt_source_next(), flt_source_stop() or
 *   flt_source_destroy() on the same source. Copy it out (the pixels are
 *   `height` rows of `stride_bytes`) to keep it longer.
 *
 * Encoder positions (encoder_mm, mm of strip travel; see lib/sources/README.md
 * for how to wire a real encoder). The option "source_encoder_mode"
 * (flt_encoder_mode: FLT_ENCODER_AUTO, _FIXED_STEP, _HOST, _CHUNK) picks:
 *   0 auto        simulator: its own encoder position; images: the CSV file
 *                 when one is given, else fixed step; camera: fixed step.
 *   1 fixed step  encoder_mm = source_encoder_start + source_encoder_step *
 *                 (block_id - first block id). Block ids count every frame
 *                 the camera took, so frames lost on the way keep their
 *                 travel (a triggered camera takes one frame per step).
 *   2 host        the host reads its encoder itself and calls
 *                 flt_source_set_encoder(); each frame carries the value
 *                 set last before flt_source_next() returned it (NaN before
 *                 the first call).
 *   3 chunk       a USB3 Vision camera counting encoder pulses appends the
 *                 count as a chunk (id source_encoder_chunk_id, a 32- or
 *                 64-bit little-endian counter); encoder_mm =
 *                 source_encoder_start + source_encoder_mm_per_count *
 *                 count, with 32-bit wraps unrolled.
 *
 * Frame bounds (cameras)
 *   A camera says how large its frames are (Width, Height, PixelFormat),
 *   and a wrong or hostile camera can say anything. flt_source_start()
 *   checks the sizes before anything is allocated: each side 1 ..
 *   FLT_CALIB_MAX_FRAME_SIDE px (16384, the bound of the whole library),
 *   Mono8, Mono10, Mono12 or Mono16 (unpacked), so a frame is at most
 *   512 MiB; everything else is FLT_ERR_DEVICE (FLT_ERR_FORMAT for the
 *   pixel format) naming the values. The buffers a camera source allocates
 *   (frame slots, transfers) together stay within
 *   FLT_SOURCE_MAX_BUFFER_BYTES: GigE Vision assembles fewer frames at once
 *   than gige_assembly_frames when that many would not fit (never fewer
 *   than one, with the one lent to the caller); USB3 Vision refuses a
 *   stream set-up that would not fit. Every frame delivered, of every kind
 *   of source, lies in its buffer: `height` rows of `stride_bytes`, the
 *   last one `width` pixels, and a leader that announces another size or
 *   format than the stream's is never delivered (BAD_LEADERS).
 *
 * Frame accounting (USB3 Vision)
 *   A frame that arrives damaged is dropped and counted, and the next good
 *   frame is delivered by the same flt_source_next() call when it arrives
 *   in time; the reason of the last drop is flt_source_stream_error().
 *   The outcome of each failure mode seen in the field:
 *     short frame     (payload sum != trailer's valid size or < image size,
 *                     or a non-zero trailer status)  DROPPED, SHORT
 *     new leader while a frame is open               DROPPED, INCOMPLETE
 *     overflow (a transfer bigger than its buffer, or more payload than
 *                     the stream was set up for)     DROPPED, OVERFLOW
 *     skipped block ids                 LOST += the ids missing (the frame
 *                                       after the gap is delivered)
 *     bulk submit refused (usbfs memory) SUBMIT_REFUSED; the open frame, or
 *                                       the next one if none is open, is
 *                                       DROPPED (SUBMIT_DROPPED: the camera
 *                                       may have sent data nobody was waiting
 *                                       for); the transfer is submitted again
 *                                       on the next completion or call;
 *                                       FLT_ERR_DEVICE if none can be submitted
 *   The rest of a dropped frame (its payload, its trailer) is discarded
 *   silently until the next leader; data outside any frame is BAD_PACKETS.
 *     no data within the timeout        TIMEOUTS; flt_source_next() returns
 *                                       FLT_ERR_TIMEOUT; a partial frame is
 *                                       DROPPED
 *     camera unplugged                  DISCONNECTS; FLT_ERR_DEVICE now and on
 *                                       every later call; destroy still works
 *     garbage transfers                 BAD_PACKETS
 *   The control channel counts PENDING_ACKS, STALE_ACKS and COMMAND_RETRIES.
 *   A camera that keeps answering "pending" is given up 10 s after its
 *   first pending acknowledge (FLT_ERR_TIMEOUT; both transports), whatever
 *   time the acknowledges ask for.
 *
 * Frame accounting (GigE Vision)
 *   The network is hostile (docs/gigevision.md): only the camera speaks,
 *   and one packet can neither stop the stream nor get a frame delivered
 *   damaged. A datagram on the stream socket from another address than the
 *   camera's, or another port than its stream source port (the one it
 *   reports, or that of the first leader after start), and one on the
 *   control socket from anyone but the camera's GVCP port, is BAD_PACKETS
 *   and ignored. A frame opens only at its leader, at most
 *   4 x gige_assembly_frames block ids ahead of the newest frame. A packet
 *   further away is BAD_PACKETS, but one of a block the stream passed up to
 *   16 x gige_assembly_frames ago is a late DUPLICATE; a camera that
 *   restarts its block ids is recognised by two leaders. A packet is
 *   missing once a later packet (of its frame or of a later one) arrived
 *   and then gige_resend_timeout passed or 64 more packets arrived, or once
 *   its frame fell silent for gige_resend_timeout: two packets that
 *   overtake each other are no loss. Each packet found missing counts
 *   PACKETS_MISSING and is asked again (RESEND_REQUESTS per request); one
 *   that then arrives counts PACKETS_RESENT; a copy of a packet already
 *   here, DUPLICATE (a copy with other bytes: BAD_PACKETS, and its frame is
 *   dropped). A frame still missing packets after gige_resend_attempts
 *   requests (or at once, when the camera does not resend), or pushed out
 *   by gige_assembly_frames later frames in assembly, is DROPPED and
 *   INCOMPLETE, and the packets it lacked count PACKETS_MISSING; a leader
 *   announcing another size, format or padding than the stream's,
 *   BAD_LEADERS; a payload packet of the wrong size, OVERFLOW; block ids
 *   never seen inside that window, LOST; TIMEOUTS as for USB3 Vision. So
 *   PACKETS_MISSING = PACKETS_RESENT + the packets of the frames dropped
 *   for them, and FRAMES + DROPPED + LOST = the block ids from the first
 *   frame to the last.
 *
 * GenICam features (USB3 Vision)
 *   Opening a camera reads its bootstrap registers, its manifest and its
 *   GenICam XML (zipped or not). Features are evaluated by name when used,
 *   reading the camera each time, by the library's GenICam engine (every
 *   node kind: registers, bit fields, StructReg entries, formulas -
 *   SwissKnife, Converter and their integer forms -, computed addresses,
 *   selectors; see flatline/genicam.h, which shows the same evaluation
 *   without a camera). The access mode is honoured: a feature that is not
 *   implemented, not available, locked or read-only is refused with
 *   FLT_ERR_STATE; a value outside its bounds with FLT_ERR_INVALID_ARGUMENT.
 *   A feature the camera lacks fails with FLT_ERR_NOT_FOUND, one whose
 *   description the engine refuses (wrong or ambiguous there) with
 *   FLT_ERR_FORMAT, a formula failing for the camera's values with
 *   FLT_ERR_NUMERIC; each names the node chain, and
 *   flt_source_map_feature() gives such a feature a register by address
 *   instead. While streaming the client holds TLParamsLocked = 1 (when the
 *   camera has it), so features that change the payload are locked, as
 *   cameras expect. Streaming needs Width, Height,
 *   PixelFormat, AcquisitionMode, AcquisitionStart and AcquisitionStop; a
 *   laser-line sensor typically also sets OffsetY, Height, ExposureTime and
 *   TriggerSelector/TriggerMode/TriggerSource before flt_source_start().
 *
 * Threads
 *   A source must not be used from two threads at once. Different sources
 *   are independent.
 *
 * Testing without a camera
 *   flatline/testing.h (a separate library, outside the ABI promise) has a
 *   simulated USB bus of simulated cameras with fault injection; its
 *   transport goes where the functions below take a flt_usb_transport.
 */
#ifndef FLATLINE_SOURCE_H
#define FLATLINE_SOURCE_H

#include "flatline/coil.h"
#include "flatline/common.h"
#include "flatline/extractor.h"
#include "flatline/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The most bytes of frame buffers one camera source allocates (1 GiB):
 * see "Frame bounds". */
#define FLT_SOURCE_MAX_BUFFER_BYTES 1073741824

/** A frame source (opaque handle). */
typedef struct flt_source flt_source;
/** A frame borrowed from its source (see "Frame memory and lifetime"). */
typedef struct flt_frame flt_frame;
/** A snapshot of the cameras present. */
typedef struct flt_camera_list flt_camera_list;
/**
 * The USB access through which USB3 Vision cameras are found and opened.
 * NULL, wherever a function takes one, is the computer's USB bus through
 * libusb-1.0: the only transport of libflatline itself. Other transports
 * (a simulated bus of simulated cameras) come only from the testing
 * library, flatline/testing.h; they belong to whoever made them.
 */
typedef struct flt_usb_transport flt_usb_transport;

/** Values of the option "source_encoder_mode" (FLT_OPT_SOURCE_ENCODER_MODE):
 * where a frame's encoder position comes from (see "Encoder positions");
 * the bindings' names in quotes. */
typedef enum flt_encoder_mode {
    /** "auto": the simulator's own, an image CSV file, else fixed step. */
    FLT_ENCODER_AUTO = 0,
    /** "fixed_step": source_encoder_start + source_encoder_step * block. */
    FLT_ENCODER_FIXED_STEP = 1,
    /** "host": the value last given to flt_source_set_encoder(). */
    FLT_ENCODER_HOST = 2,
    /** "chunk": the camera's encoder counter chunk. */
    FLT_ENCODER_CHUNK = 3,
    /** Not a value: keeps the type int-sized. */
    FLT_ENCODER_MODE_MAX_ENUM_ = 0x7FFFFFFF
} flt_encoder_mode;

/** What a source reads its frames from. */
typedef enum flt_source_kind {
    FLT_SOURCE_SIMULATOR = 1, /**< a simulated sensor (flt_sim) */
    FLT_SOURCE_IMAGES = 2,    /**< recorded images */
    FLT_SOURCE_U3V = 3,       /**< a USB3 Vision camera */
    FLT_SOURCE_GIGE = 4,      /**< a GigE Vision camera */
    FLT_SOURCE_RECORDING = 5, /**< a recording (flatline/record.h) */
    FLT_SOURCE_KIND_MAX_ENUM_ = 0x7FFFFFFF
} flt_source_kind;

/* ---------------------------------------------------------------------- */
/* Creating a source                                                       */
/* ---------------------------------------------------------------------- */

/** A source of rendered frames from a simulator (flt_sim_next_frame), each
 * with the simulator's own encoder position (encoder mode 0), or the mode's
 * value for modes 1 and 2; mode 3 is refused. `sim` is borrowed: it must
 * outlive the source, and the caller may still change its sheet between
 * frames. Block ids count from 0; timestamps are the host's monotonic clock,
 * ns. Allocates one frame buffer.
 * @param sim     the simulator (borrowed).
 * @param options NULL, or the source_* keys.
 * @param out     receives the source.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument (encoder mode 3, a
 * simulator that cannot render frames); FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_create_sim(flt_sim *sim,
                                                                const flt_options *options,
                                                                flt_source **out);

/** A source reading `count` image files (PNG, TIFF or anything OpenCV's
 * imread reads), in the given order. Every file must be single-channel, 8 or
 * 16 bits, and the size of the first. 8-bit files give Mono8; 16-bit files
 * give Mono16, or Mono10/Mono12 when the option source_image_bits says so.
 *   paths        [count] file names, copied (count >= 1).
 *   encoder_csv  NULL, or a CSV file of the encoder positions, mm, one row
 *                per image in order: either "encoder_mm" or
 *                "file name,encoder_mm" (then the name must match the
 *                image's name without its folder). Lines starting with '#'
 *                and a first line whose last field is not a number (a
 *                header) are skipped. Read and checked here: a wrong row
 *                count or a bad number fails with FLT_ERR_FORMAT naming the
 *                line.
 * Without a CSV the positions follow the fixed step. Block id = index of the
 * file. Timestamps are the host's monotonic clock, ns. The first file is read
 * here to learn the size. After the last image flt_source_next() gives
 * FLT_OK with *out = NULL.
 * @param paths       [count] file names.
 * @param count       the number of files.
 * @param encoder_csv NULL, or the CSV file of positions.
 * @param options     NULL, or the source_* keys.
 * @param out         receives the source.
 * @return FLT_OK; FLT_ERR_IO for a file that cannot be read; FLT_ERR_FORMAT
 *         as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_create_images(const char *const *paths,
                                                                   size_t count,
                                                                   const char *encoder_csv,
                                                                   const flt_options *options,
                                                                   flt_source **out);

/** The same for every *.png, *.tif and *.tiff file of `directory` (not its
 * sub-folders), sorted by name (byte order). FLT_ERR_NOT_FOUND if there is
 * none.
 * @param directory   the folder.
 * @param encoder_csv NULL, or the CSV file of positions.
 * @param options     NULL, or the source_* keys.
 * @param out         receives the source.
 * @return as flt_source_create_images(); FLT_ERR_NOT_FOUND as above.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_create_image_dir(const char *directory,
                                                                      const char *encoder_csv,
                                                                      const flt_options *options,
                                                                      flt_source **out);

/**
 * Lists the USB3 Vision cameras present. Devices that are not USB3 Vision
 * are skipped; cameras that cannot be opened to read their strings (no udev
 * rule, no WinUSB driver) are listed with vendor "?" and the reason as their
 * model.
 * @param usb  NULL: the USB bus through libusb; else a transport of the
 *             testing library (flatline/testing.h).
 * @param out  the new list (flt_camera_list_destroy()).
 * @return FLT_OK; FLT_ERR_DEVICE if libusb cannot start;
 *         FLT_ERR_INVALID_ARGUMENT for a transport of another release.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_camera_list_create(flt_usb_transport *usb,
                                                                 flt_camera_list **out);
/** Frees the list; NULL is a no-op.
 * @param list the list, or NULL.
 */
FLT_API void FLT_CALL flt_camera_list_destroy(flt_camera_list *list);
/** The number of cameras in the list.
 * @param list the list.
 * @param out  receives the number of cameras.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_camera_list_count(const flt_camera_list *list,
                                                                size_t *out);
/** Camera `index`: its strings (owned by the list, valid until it is
 * destroyed) and its link speed. Any output may be NULL.
 * @param list           the list.
 * @param index          0 .. count - 1.
 * @param vendor_out     the vendor's name.
 * @param model_out      the model's name.
 * @param serial_out     the serial number.
 * @param speed_mbps_out the link speed, Mbit/s (480 high speed, 5000 super
 *                       speed, 10000 super speed plus; 0 unknown).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL list or an index out
 *         of range.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_camera_list_get(const flt_camera_list *list,
                                                              size_t index, const char **vendor_out,
                                                              const char **model_out,
                                                              const char **serial_out,
                                                              uint32_t *speed_mbps_out);

/**
 * Opens a USB3 Vision camera. Reads the bootstrap registers and the GenICam
 * XML, and leaves a camera that a killed process left streaming stopped
 * (AcquisitionStop, SI control = 0, stream endpoint halt cleared). The
 * stream buffers are allocated by flt_source_start().
 * @param usb     NULL: the USB bus through libusb; else a transport of the
 *                testing library (flatline/testing.h), which must outlive
 *                the source.
 * @param serial  the camera with that serial number; NULL: the first one.
 * @param options source_* and u3v_* options, or NULL for the defaults.
 * @param out     the new source (flt_source_destroy()).
 * @return FLT_OK; FLT_ERR_NOT_FOUND naming a serial that is not present;
 *         FLT_ERR_DEVICE saying why a camera cannot be opened (permissions:
 *         see lib/sources/deploy/); FLT_ERR_INVALID_ARGUMENT for a
 *         transport of another release.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_open_u3v(flt_usb_transport *usb,
                                                              const char *serial,
                                                              const flt_options *options,
                                                              flt_source **out);

/* ---------------------------------------------------------------------- */
/* GigE Vision cameras                                                     */
/* ---------------------------------------------------------------------- */
/*
 * A GigE Vision camera is reached over UDP (no camera SDK): GVCP on the
 * camera's port 3956 for registers, GVSP from the camera to a host port for
 * frames (lib/sources/gige/README.md). Opening takes the
 * camera's control privilege and keeps it with a heartbeat thread (every
 * third of option gige_heartbeat_timeout); another application cannot
 * control the camera meanwhile. Registers are big-endian; features go
 * through the same GenICam engine as USB3 Vision. The stream packet size is
 * negotiated with test packets (option gige_packet_size); lost packets are
 * asked again (gige_resend_attempts, gige_resend_timeout) when the camera
 * resends (FLT_CAMERA_RESEND_CAPABLE). Frames leave in block order; a frame
 * still missing packets after the resends is dropped, never delivered
 * damaged (see "Frame accounting"). The host's firewall must let the
 * camera's UDP packets in.
 */

/** Lists the GigE Vision cameras that answer a discovery command.
 * Each entry has the strings of flt_camera_list_get (speed 0) and an
 * address (flt_camera_list_address).
 * @param address     "a.b.c.d" (a camera, or a subnet's broadcast address;
 *                    ":port" for a GVCP port other than 3956), or NULL for
 *                    255.255.255.255 and every IPv4 interface's broadcast
 *                    address.
 * @param timeout_ms  how long answers are gathered, ms (1..60000).
 * @param out         the new list (flt_camera_list_destroy).
 * @return FLT_OK (an empty list when nobody answers);
 *         FLT_ERR_INVALID_ARGUMENT for an address that is no IPv4 address;
 *         FLT_ERR_DEVICE when no discovery could be sent. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_camera_list_create_gige(const char *address,
                                                                      uint32_t timeout_ms,
                                                                      flt_camera_list **out);

/** The address to open camera `index` of a list by.
 * @param list   a camera list.
 * @param index  the camera, 0 .. count - 1.
 * @param out    "a.b.c.d" (":port" when it answered from another port than
 *               3956) for a GigE Vision camera, "" for a USB3 Vision one;
 *               owned by the list.
 * @return FLT_OK, or FLT_ERR_INVALID_ARGUMENT. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_camera_list_address(const flt_camera_list *list,
                                                                  size_t index, const char **out);

/** Opens a GigE Vision camera: takes the control privilege, reads the
 * bootstrap registers and the GenICam file, and negotiates the stream
 * packet size. The frame buffers are allocated by flt_source_start().
 * @param camera   its address ("a.b.c.d" or "a.b.c.d:port"), or its serial
 *                 number or user-defined name (found by a discovery
 *                 broadcast, option gige_discovery_timeout), or NULL for the
 *                 first camera that answers.
 * @param options  source_* and gige_* options, or NULL.
 * @param out      the new source (flt_source_destroy).
 * @return FLT_OK; FLT_ERR_NOT_FOUND when no such camera answers;
 *         FLT_ERR_TIMEOUT when the address does not answer; FLT_ERR_DEVICE
 *         when another application controls the camera or it refuses us;
 *         FLT_ERR_INVALID_ARGUMENT for an empty name or an option outside
 *         its range (encoder mode 3 is not available yet). */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_open_gige(const char *camera,
                                                               const flt_options *options,
                                                               flt_source **out);

/** Stops a streaming camera, releases it and frees everything. NULL is a
 * no-op.
 * @param source the source, or NULL.
 */
FLT_API void FLT_CALL flt_source_destroy(flt_source *source);

/** The kind of the source.
 * @param source the source.
 * @param out receives its kind.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_kind_of(const flt_source *source,
                                                             flt_source_kind *out);

/* ---------------------------------------------------------------------- */
/* Acquisition                                                             */
/* ---------------------------------------------------------------------- */

/** Starts acquisition. Camera: sets AcquisitionMode = Continuous, reads
 * Width, Height, PixelFormat and checks them (see "Frame bounds") before
 * anything is allocated, sets up the stream (USB3 Vision: SIRM, payload
 * transfer size a multiple of the alignment, at most u3v_transfer_size,
 * the pool of u3v_transfers bulk transfers and the frame buffer; GigE
 * Vision: the frame slots), turns the stream channel on (SI control = 1;
 * SCDA and SCP), sets TLParamsLocked = 1 and executes AcquisitionStart. A
 * camera still streaming (SI control on, or left so by a stop or start
 * that failed) is stopped first, as open does
 * (FLT_COUNT_STREAM_RECOVERIES). When a start fails after the channel was
 * turned on, it stops the camera again; if even that fails, the message
 * says the camera may still be streaming, and the next start or stop stops
 * it.
 * Simulator and images: resets the block ids (a started source starts again
 * from its first frame only for images). FLT_ERR_STATE if already started.
 * @param source the source.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_DEVICE for a size beyond
 *         the frame bounds, or from the camera; FLT_ERR_FORMAT for a pixel
 *         format not delivered; FLT_ERR_TIMEOUT from the camera;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_start(flt_source *source);

/** Stops acquisition. The source is stopped on the host side whatever the
 * camera answers (transfers cancelled, no frame until the next start).
 * Camera: AcquisitionStop, then its stream channel off, read back as off
 * (USB3 Vision: SI control = 0; GigE Vision: SCP = 0); a step whose answer
 * timed out, was busy or malformed is sent again (up to
 * u3v_command_attempts or gige_command_attempts rounds, each command with
 * its own attempts). A camera that was unplugged streams to no one: FLT_OK.
 * Stopping a stopped source is a no-op, unless its camera may still be
 * streaming.
 * @param source the source.
 * @return FLT_OK only when the camera took both; otherwise the last
 *         failure's status (FLT_ERR_TIMEOUT, FLT_ERR_DEVICE) and a message
 *         saying the camera may still be streaming: a later
 *         flt_source_stop() or flt_source_start() stops it;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_stop(flt_source *source);

/** Waits up to timeout_ms for the next good frame (see "Frame accounting").
 * *out is the borrowed frame; NULL (with FLT_OK) at the end of an image
 * sequence. FLT_ERR_TIMEOUT when no good frame came in time,
 * FLT_ERR_DEVICE when the camera is gone, FLT_ERR_STATE before start. The
 * simulator and images never wait.
 * @param source the source.
 * @param timeout_ms how long to wait, ms.
 * @param out        receives the borrowed frame, or NULL at the end.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_next(flt_source *source, uint32_t timeout_ms,
                                                          const flt_frame **out);

/** Everything about a frame; any output may be NULL.
 * @param frame            the frame (borrowed from flt_source_next).
 * @param pixels_out       height rows of stride_bytes, `format` pixels
 *                         (16-bit formats: host-order words, data in the
 *                         low bits); valid until the next flt_source_next.
 * @param width_out        width, px.
 * @param height_out       height, px.
 * @param stride_bytes_out bytes from row to row, >= width * bytes per pixel.
 * @param format_out       the pixel format.
 * @param block_id_out     the camera's frame counter (simulator and images:
 *                         the frame index).
 * @param timestamp_ns_out camera: the leader's timestamp (device clock, ns);
 *                         otherwise the host's monotonic clock at delivery,
 *                         ns.
 * @param encoder_mm_out   the strip position, mm (see "Encoder positions").
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL frame.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL
flt_frame_info(const flt_frame *frame, const void **pixels_out, uint32_t *width_out,
               uint32_t *height_out, size_t *stride_bytes_out, flt_pixel_format *format_out,
               uint64_t *block_id_out, uint64_t *timestamp_ns_out, double *encoder_mm_out);

/** Encoder mode 2: the position the next frames carry, mm (finite).
 * FLT_ERR_STATE in any other mode.
 * @param source the source.
 * @param encoder_mm the position, mm.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_set_encoder(flt_source *source,
                                                                 double encoder_mm);

/** Frame and channel counters, since the source was created. */
typedef enum flt_source_counter {
    FLT_COUNT_FRAMES = 0,  /**< good frames delivered */
    FLT_COUNT_DROPPED = 1, /**< frames that arrived damaged (sum of the
                              next five and BAD_LEADERS) */
    FLT_COUNT_SHORT = 2,   /**< short frames: payload short of the trailer's or the image size, or a
                              bad trailer status */
    FLT_COUNT_INCOMPLETE = 3, /**< a new leader arrived mid-frame */
    FLT_COUNT_OVERFLOW =
        4, /**< a transfer bigger than its buffer, or more payload than set up for */
    FLT_COUNT_SUBMIT_DROPPED = 5,  /**< frames dropped after a refused submit */
    FLT_COUNT_TIMEOUT_DROPPED = 6, /**< partial frames dropped at a timeout */
    FLT_COUNT_LOST = 7,            /**< block ids skipped (frames never seen) */
    FLT_COUNT_SUBMIT_REFUSED = 8,  /**< bulk submissions refused */
    FLT_COUNT_TIMEOUTS = 9,        /**< flt_source_next() calls that timed out */
    FLT_COUNT_DISCONNECTS = 10,    /**< times the camera was unplugged */
    FLT_COUNT_BAD_PACKETS = 11,    /**< transfers that are no leader, payload
                                      of an open frame, or trailer */
    FLT_COUNT_BAD_LEADERS = 12,    /**< leaders with an unusable format/size */
    FLT_COUNT_PENDING_ACKS =
        13,                    /**< GenCP pending acks received (the camera asked for more time) */
    FLT_COUNT_STALE_ACKS = 14, /**< acks with another request id (stale), discarded */
    FLT_COUNT_COMMAND_RETRIES = 15,   /**< GenCP commands sent again after no answer */
    FLT_COUNT_STREAM_RECOVERIES = 16, /**< cameras found streaming on open or start */
    FLT_COUNT_PACKETS_MISSING = 17,   /**< GigE: packets found missing (each once) */
    FLT_COUNT_RESEND_REQUESTS = 18,   /**< GigE: packets asked again (each time) */
    FLT_COUNT_PACKETS_RESENT = 19,    /**< GigE: missing packets that came after a
                                         request */
    FLT_COUNT_PACKETS_DUPLICATE = 20, /**< GigE: packets that came twice, or for a
                                         frame already gone */
    FLT_COUNT_MAX_ENUM_ = 0x7FFFFFFF
} flt_source_counter;

/** The value of one counter.
 * @param source the source.
 * @param counter which counter.
 * @param out     receives its value.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_count(const flt_source *source,
                                                           flt_source_counter counter,
                                                           uint64_t *out);

/** Why the last frame was dropped or lost ("" if none was). Owned by the
 * source, valid until its next call. Never NULL (for a NULL source too).
 * @param source the source.
 * @return the reason (see above).
 */
FLT_API const char *FLT_CALL flt_source_stream_error(const flt_source *source);

/* ---------------------------------------------------------------------- */
/* Cameras (USB3 Vision and GigE Vision)                                  */
/* ---------------------------------------------------------------------- */

/** Camera strings from the bootstrap registers (USB3 Vision: ABRM; GigE
 * Vision: 0x0048.., no family: ""). They are the camera's words: every
 * control byte (ESC and the rest of C0, DEL, the C1 controls) and every
 * byte that is not UTF-8 is replaced by '?' before a caller sees them,
 * here and in camera lists, so that printing them cannot drive a
 * terminal. */
typedef enum flt_camera_string {
    FLT_CAMERA_VENDOR = 0,            /**< vendor name */
    FLT_CAMERA_MODEL = 1,             /**< model name */
    FLT_CAMERA_FAMILY = 2,            /**< family name */
    FLT_CAMERA_DEVICE_VERSION = 3,    /**< device version */
    FLT_CAMERA_MANUFACTURER_INFO = 4, /**< manufacturer information */
    FLT_CAMERA_SERIAL = 5,            /**< serial number */
    FLT_CAMERA_USER_NAME = 6,         /**< user-defined name */
    FLT_CAMERA_STRING_MAX_ENUM_ = 0x7FFFFFFF
} flt_camera_string;

/** The string (owned by the source, valid until it is destroyed).
 * FLT_ERR_STATE for a source that is not a camera.
 * @param source the source.
 * @param which the string wanted.
 * @param out   receives it.
 * @return FLT_OK; FLT_ERR_STATE for a source that is not a camera;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_camera_string(const flt_source *source,
                                                                   flt_camera_string which,
                                                                   const char **out);

/** Camera values read from the registers or chosen for the stream. */
typedef enum flt_camera_value {
    FLT_CAMERA_GENCP_VERSION = 0,         /**< ABRM 0x000 (major << 16 | minor) */
    FLT_CAMERA_U3V_VERSION = 1,           /**< SBRM 0x00 */
    FLT_CAMERA_RESPONSE_TIME_MS = 2,      /**< ABRM max device response time */
    FLT_CAMERA_CONTROL_TIMEOUT_MS = 3,    /**< max(u3v_control_timeout, above) */
    FLT_CAMERA_MAX_COMMAND_BYTES = 4,     /**< SBRM max command transfer */
    FLT_CAMERA_MAX_ACK_BYTES = 5,         /**< SBRM max ack transfer */
    FLT_CAMERA_SIRM_ADDRESS = 6,          /**< SBRM: address of the SIRM */
    FLT_CAMERA_MANIFEST_ADDRESS = 7,      /**< ABRM: address of the manifest table */
    FLT_CAMERA_XML_BYTES = 8,             /**< the XML file as stored (zipped size) */
    FLT_CAMERA_XML_ZIPPED = 9,            /**< 1 when it was a ZIP */
    FLT_CAMERA_SPEED_MBPS = 10,           /**< link speed, Mbit/s */
    FLT_CAMERA_ALIGNMENT = 11,            /**< SIRM, bytes (after start) */
    FLT_CAMERA_PAYLOAD_BYTES = 12,        /**< SIRM required payload size */
    FLT_CAMERA_TRANSFER_BYTES = 13,       /**< payload transfer size written */
    FLT_CAMERA_TRANSFER_COUNT = 14,       /**< payload transfers per frame */
    FLT_CAMERA_FINAL_TRANSFER_BYTES = 15, /**< final transfer size written */
    FLT_CAMERA_MAX_LEADER_BYTES = 16,     /**< SIRM maximum leader size */
    FLT_CAMERA_MAX_TRAILER_BYTES = 17,    /**< SIRM maximum trailer size */
    /* GigE Vision (also CONTROL_TIMEOUT_MS, XML_BYTES, XML_ZIPPED and,
     * after start, PAYLOAD_BYTES) */
    FLT_CAMERA_GEV_VERSION = 18,          /**< bootstrap 0x0000 (major << 16 | minor) */
    FLT_CAMERA_IP_ADDRESS = 19,           /**< IPv4 address, a << 24 | b << 16 | ... */
    FLT_CAMERA_HEARTBEAT_TIMEOUT_MS = 20, /**< the heartbeat timeout written */
    FLT_CAMERA_HEARTBEATS = 21,           /**< heartbeats answered since open */
    FLT_CAMERA_PACKET_SIZE = 22,          /**< negotiated stream packet size, bytes
                                             (IP + UDP + GVSP headers + data) */
    FLT_CAMERA_STREAM_PORT = 23,          /**< host UDP port of the stream */
    FLT_CAMERA_TIMESTAMP_HZ = 24,         /**< camera timestamp ticks per second */
    FLT_CAMERA_RESEND_CAPABLE = 25,       /**< 1 when the camera resends packets */
    FLT_CAMERA_RECEIVE_BUFFER_BYTES = 26, /**< the stream socket's buffer, as
                                             the system granted it */
    FLT_CAMERA_VALUE_MAX_ENUM_ = 0x7FFFFFFF
} flt_camera_value;

/** One camera value. FLT_ERR_STATE for a source that is not a camera.
 * @param source the source.
 * @param which the value wanted.
 * @param out   receives it.
 * @return FLT_OK; FLT_ERR_STATE for a source that is not a camera;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_camera_value(const flt_source *source,
                                                                  flt_camera_value which,
                                                                  uint64_t *out);

/** @{ */
/** GenICam features by name (e.g. "Width", "ExposureTime", "TriggerMode").
 * Integers: integer features, Boolean, and Enumeration (its value); floats:
 * float features (Float, FloatReg, Converter, SwissKnife; integers
 * converted); enumerations by entry name ("Continuous"); commands write
 * their command value. A value is checked against the feature's bounds
 * (pMin/pMax/pInc, its register's width), then the camera checks it and
 * answers a GenCP status, which the error message names. FLT_ERR_STATE for
 * a source that is not a camera, or a feature its access mode forbids (see
 * "GenICam features" above). */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_get_int(flt_source *source,
                                                             const char *feature, int64_t *out);
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_set_int(flt_source *source,
                                                             const char *feature, int64_t value);
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_get_float(flt_source *source,
                                                               const char *feature, double *out);
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_set_float(flt_source *source,
                                                               const char *feature, double value);
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_set_enum(flt_source *source,
                                                              const char *feature,
                                                              const char *entry);
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_execute(flt_source *source,
                                                             const char *feature);
/** @} */

/** Gives feature `feature` a register instead of its XML node (for a
 * feature the camera's description lacks or the engine refuses, or to
 * override one): `length` bytes (1, 2, 4 or
 * 8) at `address`, little-endian; an unsigned integer, or an IEEE float
 * (length 4 or 8) when is_float is non-zero. Commands write 1 to it.
 * Enumerations mapped this way take their integer values (set_int).
 * @param source the source.
 * @param feature  the feature's name.
 * @param address  the register's address.
 * @param length   its length in bytes.
 * @param is_float non-zero for an IEEE float.
 * @return FLT_OK; FLT_ERR_STATE for a source that is not a camera;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_map_feature(flt_source *source,
                                                                 const char *feature,
                                                                 uint64_t address, uint32_t length,
                                                                 int is_float);

/** @{ */
/** Raw register access through GenCP (chunked to the camera's limits). */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_read_memory(flt_source *source,
                                                                 uint64_t address, void *out,
                                                                 size_t bytes);
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_write_memory(flt_source *source,
                                                                  uint64_t address,
                                                                  const void *bytes_in,
                                                                  size_t bytes);
/** @} */

/* ---------------------------------------------------------------------- */
/* Recordings (flatline/record.h)                                          */
/* ---------------------------------------------------------------------- */
/*
 * A recording replays as a source: one frame per recorded row, in order,
 * with the row's encoder position (encoder mode auto only), its host time
 * (UTC, ns) as the timestamp and its number as the block id. A frame
 * carries its profile row (flt_frame_row), the events recorded before it
 * (flt_frame_event: cuts, coils, flushes, gaps of lost rows) and, where the
 * recorder kept the camera frame, its pixels; otherwise flt_frame_info()
 * gives NULL pixels and a size of 0. Events recorded after the last row
 * come with one more frame that has no row. The end is FLT_OK with a NULL
 * frame, as for images; flt_source_start() starts again from the first
 * row. A gauge attached to a recording (flt_gauge_attach_source) replays
 * it: the same options give the same sheets bit for bit (flatline/gauge.h,
 * "Recordings").
 */

/** What a recorded event is (flt_frame_event). */
typedef enum flt_recorded_event {
    /** The shear cut at the event's encoder_mm (flt_gauge_cut). */
    FLT_RECORDED_CUT = 0,
    /** A coil's identity was given (flt_gauge_set_coil): see coil_out. */
    FLT_RECORDED_COIL = 1,
    /** The input was flushed (flt_gauge_flush) before this frame. */
    FLT_RECORDED_FLUSH = 2,
    /** Rows were lost before this frame (the recorder's writer was behind):
     * count_out says how many. */
    FLT_RECORDED_GAP = 3,
    /** A note (flt_gauge_note): see flt_frame_event_note(). */
    FLT_RECORDED_NOTE = 4,
    FLT_RECORDED_EVENT_MAX_ENUM_ = 0x7FFFFFFF
} flt_recorded_event;

/** A source that replays a recording (flatline/record.h).
 * @param path    the recording (UTF-8).
 * @param options NULL, or the source_* keys (source_encoder_mode must be
 *                "auto": positions are the recorded ones).
 * @param out     receives the source.
 * @return FLT_OK; FLT_ERR_IO or FLT_ERR_FORMAT as flt_recording_open();
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument or another encoder
 *         mode.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_source_open_recording(const char *path,
                                                                    const flt_options *options,
                                                                    flt_source **out);

/** The profile row of a recording's frame, as the gauge measured it: the
 * heights each laser saw, quantized (flatline/record.h). Any output may be
 * NULL.
 * @param frame      a frame of a recording source.
 * @param fibers     must equal the recording's fiber count.
 * @param height_out [fibers] mm, NaN where the sample is not valid.
 * @param slope_out  [fibers] mm/mm, NaN likewise.
 * @param flags_out  [fibers] 0 for a valid sample, else
 *                   FLT_FLAG_INVALID_INPUT or FLT_FLAG_OFF_STRIP.
 * @return FLT_OK; FLT_ERR_NOT_FOUND for a frame without a row (not of a
 *         recording, or the one after the last row);
 *         FLT_ERR_INVALID_ARGUMENT for a NULL frame or a wrong count.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_frame_row(const flt_frame *frame, size_t fibers,
                                                        double *height_out, double *slope_out,
                                                        uint8_t *flags_out);

/** The number of events recorded before a frame (0 for a frame that is
 * not of a recording).
 * @param frame the frame.
 * @param out   receives the count.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_frame_event_count(const flt_frame *frame,
                                                                size_t *out);

/** Event `index` before a frame, in the order they were recorded. Any
 * output may be NULL.
 * @param frame          the frame.
 * @param index          0 .. flt_frame_event_count() - 1.
 * @param kind_out       receives what it is.
 * @param encoder_mm_out receives a cut's position, mm (NaN otherwise).
 * @param count_out      receives a gap's lost rows (0 otherwise).
 * @param coil_out       receives a coil's identity (NULL otherwise),
 *                       lent: valid while the source lives.
 * @return FLT_OK; FLT_ERR_NOT_FOUND past the last event;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL frame.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_frame_event(const flt_frame *frame, size_t index,
                                                          flt_recorded_event *kind_out,
                                                          double *encoder_mm_out,
                                                          uint64_t *count_out,
                                                          const flt_coil_info **coil_out);

/** The kind and text of a note event (FLT_RECORDED_NOTE) before a frame.
 * Either output may be NULL.
 * @param frame    the frame.
 * @param index    the event, 0 .. flt_frame_event_count() - 1.
 * @param kind_out receives the note's kind, owned by the source.
 * @param text_out receives its text, owned by the source.
 * @return FLT_OK; FLT_ERR_NOT_FOUND past the last event or for an event
 *         that is no note; FLT_ERR_INVALID_ARGUMENT for a NULL frame.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_frame_event_note(const flt_frame *frame, size_t index,
                                                               const char **kind_out,
                                                               const char **text_out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_SOURCE_H */
