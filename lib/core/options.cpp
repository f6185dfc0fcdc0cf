// SPDX-License-Identifier: Apache-2.0
#include "core/options.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.hpp"
#include "flatline/flatness.h"
#include "flatline/gauge.h"
#include "flatline/recon.h"
#include "flatline/record.h"
#include "flatline/sim.h"
#include "flatline/source.h"

namespace flt {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

// Append-only: the position in this table is the slot in flt_options::value.
const option_spec k_options[] = {
    // reconstructor
    {FLT_OPT_KNOT_SPACING, "knot_spacing", 0.0, 1.0e5, 0.0, false},
    {FLT_OPT_LASER_SPACING, "laser_spacing", 1.0e-3, 1.0e5, 100.0, false},
    {FLT_OPT_HEIGHT_SIGMA, "height_sigma", 1.0e-9, 1.0e6, 2.5, false},
    {FLT_OPT_SLOPE_SIGMA, "slope_sigma", 1.0e-12, 1.0e3, 1.0e-3, false},
    {FLT_OPT_CURVATURE_WEIGHT, "curvature_weight", 1.0e-12, 1.0e12, 1.0e-3, false},
    {FLT_OPT_LAG_KNOTS, "lag_knots", -1.0, 100000.0, -1.0, true},
    {FLT_OPT_MAX_GAP, "max_gap", 0.0, inf, 200.0, false},
    {FLT_OPT_ROW_CAPACITY, "row_capacity", 16.0, 1.0e8, 8192.0, true},
    {FLT_OPT_RIGID_MOTION, "rigid_motion", 0.0, 1.0, 0.0, true},
    {FLT_OPT_SHAPE_SIGMA, "shape_sigma", 1.0e-9, 1.0e6, 0.1, false},
    {FLT_OPT_CURVATURE_JUMP_WEIGHT, "curvature_jump_weight", 0.0, 1.0e12, 10.0, false},
    {FLT_OPT_ROBUST, "robust", 0.0, 2.0, 0.0, true},
    {FLT_OPT_ROBUST_ITERATIONS, "robust_iterations", 1.0, 10.0, 2.0, true},
    // calibration
    {FLT_OPT_CALIB_RANSAC, "calib_ransac", 0.0, 1.0, 0.0, true},
    {FLT_OPT_CALIB_RANSAC_THRESHOLD, "calib_ransac_threshold", 1.0e-6, 1.0e4, 1.0, false},
    {FLT_OPT_CALIB_RANSAC_ITERATIONS, "calib_ransac_iterations", 1.0, 1.0e7, 1000.0, true},
    {FLT_OPT_CALIB_RANSAC_SEED, "calib_ransac_seed", 0.0, 4294967295.0, 1.0, true},
    {FLT_OPT_CALIB_RATIONAL_DISTORTION, "calib_rational_distortion", 0.0, 1.0, 0.0, true},
    // simulated sensor
    {FLT_OPT_SIM_SEED, "sim_seed", 0.0, 4294967295.0, 1.0, true},
    {FLT_OPT_SIM_FRAME_SPACING, "sim_frame_spacing", 1.0e-3, 1.0e4, 3.0, false},
    {FLT_OPT_SIM_START, "sim_start", -1.0e9, 1.0e9, 0.0, false},
    {FLT_OPT_SIM_STRIP_WIDTH, "sim_strip_width", 1.0, 1.0e5, 2000.0, false},
    {FLT_OPT_SIM_HEAVE_SIGMA, "sim_heave_sigma", 0.0, 1.0e3, 0.0, false},
    {FLT_OPT_SIM_TILT_SIGMA, "sim_tilt_sigma", 0.0, 1.0, 0.0, false},
    {FLT_OPT_SIM_ECCENTRICITY_AMPLITUDE, "sim_eccentricity_amplitude", 0.0, 1.0e3, 0.0, false},
    {FLT_OPT_SIM_ECCENTRICITY_PERIOD, "sim_eccentricity_period", 1.0e-3, 1.0e6, 50.0, false},
    {FLT_OPT_SIM_SHEAR_AMPLITUDE, "sim_shear_amplitude", 0.0, 1.0e3, 0.0, false},
    {FLT_OPT_SIM_SHEAR_DECAY, "sim_shear_decay", 0.0, 1.0e3, 0.07, false},
    {FLT_OPT_SIM_SHEAR_PERIOD, "sim_shear_period", 1.0e-3, 1.0e6, 10.0, false},
    {FLT_OPT_SIM_SHEAR_INTERVAL, "sim_shear_interval", 1.0, 1.0e9, 3000.0, false},
    {FLT_OPT_SIM_PEAK_SIGMA, "sim_peak_sigma", 0.0, 100.0, 0.0, false},
    {FLT_OPT_SIM_BIT_DEPTH, "sim_bit_depth", 8.0, 16.0, 8.0, true},
    {FLT_OPT_SIM_LINE_SIGMA, "sim_line_sigma", 0.3, 50.0, 2.0, false},
    {FLT_OPT_SIM_LINE_PEAK, "sim_line_peak", 0.0, 10.0, 0.6, false},
    {FLT_OPT_SIM_BACKGROUND, "sim_background", 0.0, 1.0, 0.03, false},
    {FLT_OPT_SIM_SPECKLE, "sim_speckle", 0.0, 1.0, 0.05, false},
    {FLT_OPT_SIM_FULL_WELL, "sim_full_well", 0.0, 1.0e9, 10000.0, false},
    {FLT_OPT_SIM_REFLECTIONS, "sim_reflections", 0.0, 1000.0, 0.0, false},
    // frame-to-profile extractor
    {FLT_OPT_EXTRACT_LASER0_FIRST_ROW, "extract_laser0_first_row", 0.0, 65535.0, 0.0, true},
    {FLT_OPT_EXTRACT_LASER0_ROWS, "extract_laser0_rows", 0.0, 65536.0, 0.0, true},
    {FLT_OPT_EXTRACT_LASER1_FIRST_ROW, "extract_laser1_first_row", 0.0, 65535.0, 0.0, true},
    {FLT_OPT_EXTRACT_LASER1_ROWS, "extract_laser1_rows", 0.0, 65536.0, 0.0, true},
    {FLT_OPT_EXTRACT_SG_WINDOW, "extract_sg_window", 3.0, 31.0, 11.0, true},
    {FLT_OPT_EXTRACT_SG_ORDER, "extract_sg_order", 1.0, 6.0, 2.0, true},
    {FLT_OPT_EXTRACT_MIN_PEAK, "extract_min_peak", 0.0, 1.0, 0.1, false},
    {FLT_OPT_EXTRACT_MAX_WIDTH, "extract_max_width", 1.0, 1000.0, 12.0, false},
    // flatness metrics
    {FLT_OPT_FLAT_WINDOW_LENGTH, "flat_window_length", 0.0, 1.0e7, 3000.0, false},
    {FLT_OPT_FLAT_UPDATE_INTERVAL, "flat_update_interval", 0.0, 1.0e7, 1000.0, false},
    {FLT_OPT_FLAT_ZONE_WIDTH, "flat_zone_width", 1.0e-3, 1.0e6, 50.0, false},
    {FLT_OPT_FLAT_REFERENCE, "flat_reference", 0.0, 1.0, 0.0, true},
    {FLT_OPT_FLAT_MIN_LENGTH, "flat_min_length", 1.0e-3, 1.0e7, 500.0, false},
    {FLT_OPT_FLAT_MIN_COVERAGE, "flat_min_coverage", 1.0e-3, 1.0, 0.8, false},
    {FLT_OPT_FLAT_WAVE_HYSTERESIS, "flat_wave_hysteresis", 1.0e-9, 1.0e4, 0.3, false},
    {FLT_OPT_FLAT_FLAT_LIMIT, "flat_flat_limit", 0.0, 1.0e7, 5.0, false},
    {FLT_OPT_FLAT_BOW_LIMIT, "flat_bow_limit", 0.0, 1.0e6, 2.0, false},
    {FLT_OPT_FLAT_CROSSBOW_LIMIT, "flat_crossbow_limit", 0.0, 1.0e6, 2.0, false},
    {FLT_OPT_FLAT_ROW_CAPACITY, "flat_row_capacity", 16.0, 1.0e8, 4096.0, true},
    // frame sources
    {FLT_OPT_SOURCE_ENCODER_MODE, "source_encoder_mode", 0.0, 3.0, 0.0, true},
    {FLT_OPT_SOURCE_ENCODER_STEP, "source_encoder_step", 1.0e-6, 1.0e6, 3.0, false},
    {FLT_OPT_SOURCE_ENCODER_START, "source_encoder_start", -1.0e12, 1.0e12, 0.0, false},
    {FLT_OPT_SOURCE_ENCODER_MM_PER_COUNT, "source_encoder_mm_per_count", 1.0e-9, 1.0e6, 0.01,
     false},
    {FLT_OPT_SOURCE_ENCODER_CHUNK_ID, "source_encoder_chunk_id", 0.0, 4294967295.0, 1313031237.0,
     true},
    {FLT_OPT_SOURCE_IMAGE_BITS, "source_image_bits", 0.0, 16.0, 0.0, true},
    {FLT_OPT_U3V_TRANSFERS, "u3v_transfers", 2.0, 64.0, 8.0, true},
    {FLT_OPT_U3V_TRANSFER_SIZE, "u3v_transfer_size", 512.0, 16777216.0, 1048576.0, true},
    {FLT_OPT_U3V_CONTROL_TIMEOUT, "u3v_control_timeout", 1.0, 60000.0, 200.0, true},
    {FLT_OPT_U3V_PENDING_ACK_LIMIT, "u3v_pending_ack_limit", 0.0, 100.0, 5.0, true},
    {FLT_OPT_U3V_COMMAND_ATTEMPTS, "u3v_command_attempts", 1.0, 10.0, 3.0, true},
    // reconstructor (appended: a key's slot is its position in this table)
    {FLT_OPT_ROBUST_LINE_ITERATIONS, "robust_line_iterations", 1.0, 32.0, 8.0, true},
    // the gauge
    {FLT_OPT_GAUGE_WORKERS, "gauge_workers", 0.0, 64.0, 2.0, true},
    {FLT_OPT_GAUGE_QUEUE_FRAMES, "gauge_queue_frames", 0.0, 4096.0, 0.0, true},
    {FLT_OPT_GAUGE_OVERFLOW, "gauge_overflow", 0.0, 2.0, 2.0, true},
    {FLT_OPT_GAUGE_FRAME_SPACING, "gauge_frame_spacing", 1.0e-3, 1.0e4, 1.0, false},
    {FLT_OPT_GAUGE_REVERSAL_LENGTH, "gauge_reversal_length", 0.0, 1.0e9, 500.0, false},
    {FLT_OPT_GAUGE_STRIP_MIN_WIDTH, "gauge_strip_min_width", 0.0, 1.0e6, 100.0, false},
    {FLT_OPT_GAUGE_TAIL_LENGTH, "gauge_tail_length", 1.0e-3, 1.0e6, 300.0, false},
    {FLT_OPT_GAUGE_MAX_SHEET_LENGTH, "gauge_max_sheet_length", 1.0, 1.0e7, 6000.0, false},
    {FLT_OPT_GAUGE_KEEP_MAPS, "gauge_keep_maps", 0.0, 2.0, 0.0, true},
    {FLT_OPT_GAUGE_SHEET_SLOTS, "gauge_sheet_slots", 1.0, 1024.0, 4.0, true},
    {FLT_OPT_GAUGE_MIN_COVERAGE, "gauge_min_coverage", 0.0, 1.0, 0.95, false},
    {FLT_OPT_GAUGE_SHEET_BACKLOG, "gauge_sheet_backlog", 0.0, 65536.0, 16.0, true},
    {FLT_OPT_GAUGE_SATURATION_LIMIT, "gauge_saturation_limit", 0.0, 1.0, 0.05, false},
    // simulated sensor: the line in the field (appended)
    {FLT_OPT_SIM_SURROUND, "sim_surround", 0.0, 2.0, 0.0, true},
    {FLT_OPT_SIM_STRIP_OFFSET, "sim_strip_offset", -1.0e5, 1.0e5, 0.0, false},
    {FLT_OPT_SIM_WANDER_AMPLITUDE, "sim_wander_amplitude", 0.0, 1.0e4, 0.0, false},
    {FLT_OPT_SIM_WANDER_PERIOD, "sim_wander_period", 1.0, 1.0e9, 30000.0, false},
    {FLT_OPT_SIM_WANDER_SIGMA, "sim_wander_sigma", 0.0, 1.0e4, 0.0, false},
    {FLT_OPT_SIM_WANDER_LENGTH, "sim_wander_length", 100.0, 1.0e9, 20000.0, false},
    {FLT_OPT_SIM_COIL_LENGTH, "sim_coil_length", 0.0, 1.0e9, 0.0, false},
    {FLT_OPT_SIM_COIL_GAP, "sim_coil_gap", 0.0, 1.0e9, 5000.0, false},
    {FLT_OPT_SIM_SECOND_WIDTH, "sim_second_width", 0.0, 1.0e5, 0.0, false},
    {FLT_OPT_SIM_TABLE_DEPTH, "sim_table_depth", 1.0, 1.0e4, 300.0, false},
    {FLT_OPT_SIM_ROLLER_PITCH, "sim_roller_pitch", 1.0, 1.0e5, 200.0, false},
    {FLT_OPT_SIM_ROLLER_GAP, "sim_roller_gap", 0.0, 1.0e5, 60.0, false},
    {FLT_OPT_SIM_TABLE_BRIGHTNESS, "sim_table_brightness", 0.0, 10.0, 0.5, false},
    {FLT_OPT_SIM_EDGE_GLINTS, "sim_edge_glints", 0.0, 1.0, 0.0, false},
    {FLT_OPT_SIM_BLOOMING, "sim_blooming", 0.0, 1.0, 0.0, false},
    // extractor: the strip's edges (appended)
    {FLT_OPT_EXTRACT_STRIP_MIN_Z, "extract_strip_min_z", -1.0e5, 1.0e5, -100.0, false},
    {FLT_OPT_EXTRACT_EDGE_GAP, "extract_edge_gap", 0.0, 1.0e5, 50.0, false},
    {FLT_OPT_EXTRACT_MIN_STRIP_WIDTH, "extract_min_strip_width", 0.0, 1.0e5, 100.0, false},
    // flatness: zones on the strip (appended)
    {FLT_OPT_FLAT_ZONE_COUNT, "flat_zone_count", 0.0, 100000.0, 0.0, true},
    {FLT_OPT_FLAT_DRIVE_SIDE, "flat_drive_side", 0.0, 1.0, 0.0, true},
    {FLT_OPT_FLAT_ZONES_ON, "flat_zones_on", 0.0, 1.0, 0.0, true},
    // GigE Vision cameras
    {FLT_OPT_GIGE_PACKET_SIZE, "gige_packet_size", 0.0, 16384.0, 0.0, true},
    {FLT_OPT_GIGE_CONTROL_TIMEOUT, "gige_control_timeout", 1.0, 60000.0, 200.0, true},
    {FLT_OPT_GIGE_COMMAND_ATTEMPTS, "gige_command_attempts", 1.0, 10.0, 3.0, true},
    {FLT_OPT_GIGE_HEARTBEAT_TIMEOUT, "gige_heartbeat_timeout", 500.0, 600000.0, 3000.0, true},
    {FLT_OPT_GIGE_RESEND_ATTEMPTS, "gige_resend_attempts", 0.0, 32.0, 3.0, true},
    {FLT_OPT_GIGE_RESEND_TIMEOUT, "gige_resend_timeout", 1.0, 10000.0, 20.0, true},
    {FLT_OPT_GIGE_SOCKET_BUFFER, "gige_socket_buffer", 65536.0, 1073741824.0, 4194304.0, true},
    {FLT_OPT_GIGE_DISCOVERY_TIMEOUT, "gige_discovery_timeout", 1.0, 60000.0, 1000.0, true},
    {FLT_OPT_GIGE_ASSEMBLY_FRAMES, "gige_assembly_frames", 2.0, 64.0, 8.0, true},
    // the leveler advisor
    {FLT_OPT_ADVISOR_DAMPING, "advisor_damping", 0.0, 1.0e6, 0.01, false},
    {FLT_OPT_ADVISOR_GAIN, "advisor_gain", 0.01, 1.0, 0.5, false},
    // reconstructor, later additions
    {FLT_OPT_LATENCY_MM, "latency_mm", 1.0, 1.0e9, 2000.0, false},
    // the quality record: recordings and the archive
    {FLT_OPT_RECORD_QUANTUM, "record_quantum", 0.000244140625, 0.0625, 0.00390625, false},
    {FLT_OPT_RECORD_COMMIT_INTERVAL, "record_commit_interval", 20.0, 1000.0, 250.0, true},
    {FLT_OPT_RECORD_SYNC, "record_sync", 0.0, 1.0, 1.0, true},
    {FLT_OPT_RECORD_QUEUE_BLOCKS, "record_queue_blocks", 2.0, 1024.0, 16.0, true},
    {FLT_OPT_RECORD_BLOCK_ROWS, "record_block_rows", 16.0, 4096.0, 256.0, true},
    {FLT_OPT_RECORD_FRAMES, "record_frames", 0.0, 2.0, 0.0, true},
    {FLT_OPT_RECORD_FRAME_SECONDS, "record_frame_seconds", 0.1, 3600.0, 10.0, false},
    {FLT_OPT_RECORD_FRAME_MB, "record_frame_mb", 1.0, 65536.0, 512.0, true},
    {FLT_OPT_RECORD_FRAMES_ON_FAIL, "record_frames_on_fail", 0.0, 1.0, 1.0, true},
    {FLT_OPT_ARCHIVE_RETENTION_DAYS, "archive_retention_days", 0.0, 36500.0, 0.0, false},
    {FLT_OPT_ARCHIVE_RETENTION_MB, "archive_retention_mb", 0.0, 1.0e9, 0.0, false},
    {FLT_OPT_ARCHIVE_BUFFER_MB, "archive_buffer_mb", 1.0, 65536.0, 256.0, true},
    {FLT_OPT_ARCHIVE_RETRY_INTERVAL, "archive_retry_interval", 10.0, 600000.0, 1000.0, true},
    {FLT_OPT_ARCHIVE_CLOSE_TIMEOUT, "archive_close_timeout", 0.0, 600000.0, 10000.0, true},
    {FLT_OPT_ARCHIVE_MAP_QUANTUM, "archive_map_quantum", 1.0e-6, 1.0, 0.001, false},
    {FLT_OPT_ARCHIVE_MAPS, "archive_maps", 0.0, 1.0, 1.0, true},
    // the gauge, later additions
    {FLT_OPT_GAUGE_PROVISIONAL_MM, "gauge_provisional_mm", 0.0, 1.0e6, 0.0, false},
    // simulator: what real photos show besides (appended)
    {FLT_OPT_SIM_DEPTH_OF_FIELD, "sim_depth_of_field", 0.0, 1.0e4, 0.0, false},
    {FLT_OPT_SIM_DARK_PATCHES, "sim_dark_patches", 0.0, 1.0, 0.0, false},
    {FLT_OPT_SIM_GAMMA, "sim_gamma", 0.2, 5.0, 1.0, false},
    {FLT_OPT_SIM_AMBIENT, "sim_ambient", 0.0, 10.0, 0.0, false},
    {FLT_OPT_SIM_TEXTURE, "sim_texture", 0.0, 1.0, 0.0, false},
};
constexpr std::size_t k_option_count = sizeof k_options / sizeof k_options[0];

// Options whose value is a choice, their values in order. The names are
// what the bindings accept for the value (robust="huber").
const option_choice k_choices[] = {
    {FLT_OPT_ROBUST, "none", FLT_ROBUST_NONE},
    {FLT_OPT_ROBUST, "huber", FLT_ROBUST_HUBER},
    {FLT_OPT_ROBUST, "tukey", FLT_ROBUST_TUKEY},
    {FLT_OPT_FLAT_REFERENCE, "shortest", FLT_FLAT_REFERENCE_SHORTEST},
    {FLT_OPT_FLAT_REFERENCE, "mean", FLT_FLAT_REFERENCE_MEAN},
    {FLT_OPT_SOURCE_ENCODER_MODE, "auto", FLT_ENCODER_AUTO},
    {FLT_OPT_SOURCE_ENCODER_MODE, "fixed_step", FLT_ENCODER_FIXED_STEP},
    {FLT_OPT_SOURCE_ENCODER_MODE, "host", FLT_ENCODER_HOST},
    {FLT_OPT_SOURCE_ENCODER_MODE, "chunk", FLT_ENCODER_CHUNK},
    {FLT_OPT_SIM_SURROUND, "strip", FLT_SIM_SURROUND_STRIP},
    {FLT_OPT_SIM_SURROUND, "nothing", FLT_SIM_SURROUND_NOTHING},
    {FLT_OPT_SIM_SURROUND, "roller_table", FLT_SIM_SURROUND_ROLLER_TABLE},
    {FLT_OPT_FLAT_DRIVE_SIDE, "low_x", FLT_SIDE_LOW_X},
    {FLT_OPT_FLAT_DRIVE_SIDE, "high_x", FLT_SIDE_HIGH_X},
    {FLT_OPT_FLAT_ZONES_ON, "strip", FLT_ZONES_ON_STRIP},
    {FLT_OPT_FLAT_ZONES_ON, "grid", FLT_ZONES_ON_GRID},
    {FLT_OPT_GAUGE_OVERFLOW, "drop", FLT_GAUGE_OVERFLOW_DROP},
    {FLT_OPT_GAUGE_OVERFLOW, "wait", FLT_GAUGE_OVERFLOW_WAIT},
    {FLT_OPT_GAUGE_OVERFLOW, "auto", FLT_GAUGE_OVERFLOW_AUTO},
    {FLT_OPT_RECORD_FRAMES, "none", FLT_RECORD_FRAMES_NONE},
    {FLT_OPT_RECORD_FRAMES, "all", FLT_RECORD_FRAMES_ALL},
    {FLT_OPT_RECORD_FRAMES, "ring", FLT_RECORD_FRAMES_RING},
};

// The components by the hundreds of their keys (common.h).
const char *const k_components[] = {
    nullptr,         "the reconstructor",  "calibration",
    "the simulator", "the extractor",      "flatness",
    "frame sources", "the gauge",          "quality verdicts",
    "the advisor",   "the quality record",
};
static_assert(k_option_count <= flt_options::max_keys,
              "grow flt_options::max_keys (it is internal, not ABI)");

std::size_t slot_of(flt_option key) {
    for (std::size_t i = 0; i < k_option_count; ++i)
        if (k_options[i].key == key)
            return i;
    return k_option_count;
}

flt_status unknown_key(const char *fn, int key) {
    return fail(FLT_ERR_NOT_FOUND, "%s: unknown option key %d", fn, key);
}

// The edit distance (insertions, deletions, substitutions) between a and b,
// for names up to 63 characters (longer: SIZE_MAX); on the stack, no heap.
std::size_t edit_distance(const char *a, const char *b) {
    constexpr std::size_t cap = 64;
    const std::size_t na = std::strlen(a), nb = std::strlen(b);
    if (na >= cap || nb >= cap)
        return static_cast<std::size_t>(-1);
    std::size_t row[cap];
    for (std::size_t j = 0; j <= nb; ++j)
        row[j] = j;
    for (std::size_t i = 1; i <= na; ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= nb; ++j) {
            const std::size_t above = row[j];
            const std::size_t replace = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
            row[j] = std::min(std::min(above + 1, row[j - 1] + 1), replace);
            diagonal = above;
        }
    }
    return row[nb];
}

}  // namespace

const char *option_component(int key) {
    const int range = key / 100;
    if (key < 0 || range >= int(sizeof k_components / sizeof k_components[0]) ||
        !k_components[range])
        return "another component";
    return k_components[range];
}

flt_status check_option_component(const char *fn, const flt_options *options,
                                  std::initializer_list<int> ranges) {
    if (!options || ranges.size() == 0)
        return FLT_OK;
    for (std::size_t i = 0; i < k_option_count; ++i) {
        const int key = int(k_options[i].key);
        if (!options->is_set[i])
            continue;
        bool read = false;
        for (int range : ranges)
            read = read || key / 100 == range / 100;
        if (!read)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: option '%s' belongs to %s, not to %s: give each component a bag "
                        "of its own options",
                        fn, k_options[i].name, option_component(key),
                        option_component(*ranges.begin()));
    }
    return FLT_OK;
}

flt_options default_options() {
    flt_options bag{};
    for (std::size_t i = 0; i < k_option_count; ++i)
        bag.value[i] = k_options[i].default_value;
    return bag;
}

flt_options component_options(const flt_options *from, int range) {
    flt_options bag = default_options();
    if (!from)
        return bag;
    for (std::size_t i = 0; i < k_option_count; ++i)
        if (int(k_options[i].key) / 100 == range / 100 && from->is_set[i]) {
            bag.value[i] = from->value[i];
            bag.is_set[i] = true;
        }
    return bag;
}

const option_spec *find_option(flt_option key) {
    std::size_t i = slot_of(key);
    return i < k_option_count ? &k_options[i] : nullptr;
}

double option_value(const flt_options *options, flt_option key) {
    std::size_t i = slot_of(key);
    if (i == k_option_count)
        throw error(FLT_ERR_INTERNAL, "unregistered option key");
    return options ? options->value[i] : k_options[i].default_value;
}

bool option_is_set(const flt_options *options, flt_option key) {
    std::size_t i = slot_of(key);
    if (i == k_option_count)
        throw error(FLT_ERR_INTERNAL, "unregistered option key");
    return options != nullptr && options->is_set[i];
}

}  // namespace flt

using namespace flt;

extern "C" {

FLT_API flt_status FLT_CALL flt_options_create(flt_options **out) {
    return guard("flt_options_create", [&] {
        FLT_CHECK_NOT_NULL("flt_options_create", out);
        *out = nullptr;
        auto *bag = new flt_options;
        for (std::size_t i = 0; i < k_option_count; ++i) {
            bag->value[i] = k_options[i].default_value;
            bag->is_set[i] = false;
        }
        *out = bag;
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_options_destroy(flt_options *options) {
    delete options;
}

FLT_API flt_status FLT_CALL flt_options_set(flt_options *options, flt_option key, double value) {
    const char *fn = "flt_options_set";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, options);
        const option_spec *spec = enum_arg(key) < 0 ? nullptr : find_option(key);
        if (!spec)
            return unknown_key(fn, enum_arg(key));
        if (std::isnan(value))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: option '%s' is NaN", fn, spec->name);
        if (value < spec->min_value || value > spec->max_value)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: option '%s' = %g is outside [%g, %g]", fn,
                        spec->name, value, spec->min_value, spec->max_value);
        if (spec->is_integer && value != std::floor(value))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: option '%s' = %g must be a whole number", fn,
                        spec->name, value);
        options->value[slot_of(key)] = value;
        options->is_set[slot_of(key)] = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_options_get(const flt_options *options, flt_option key,
                                            double *out) {
    const char *fn = "flt_options_get";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, options);
        FLT_CHECK_NOT_NULL(fn, out);
        if (enum_arg(key) < 0 || !find_option(key))
            return unknown_key(fn, enum_arg(key));
        *out = options->value[slot_of(key)];
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_option_find(const char *name, flt_option *out) {
    const char *fn = "flt_option_find";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, name);
        FLT_CHECK_NOT_NULL(fn, out);
        for (const option_spec &spec : k_options)
            if (std::strcmp(spec.name, name) == 0) {
                *out = spec.key;
                return FLT_OK;
            }
        // The closest name, when it is close (a typo, a letter or two per
        // word): "did you mean 'rigid_motion'?".
        const char *closest = nullptr;
        std::size_t best = std::strlen(name) / 3 + 1;  // at most a third of it wrong
        for (const option_spec &spec : k_options) {
            const std::size_t d = edit_distance(name, spec.name);
            if (d < best) {
                best = d;
                closest = spec.name;
            }
        }
        if (closest)
            return fail(FLT_ERR_NOT_FOUND, "%s: no option is named '%.200s'; did you mean '%s'?",
                        fn, name, closest);
        return fail(FLT_ERR_NOT_FOUND, "%s: no option is named '%.200s'", fn, name);
    });
}

FLT_API flt_status FLT_CALL flt_option_info(flt_option key, const char **name_out, double *min_out,
                                            double *max_out, double *default_out,
                                            int *is_integer_out) {
    const char *fn = "flt_option_info";
    return guard(fn, [&] {
        const option_spec *spec = enum_arg(key) < 0 ? nullptr : find_option(key);
        if (!spec)
            return unknown_key(fn, enum_arg(key));
        if (name_out)
            *name_out = spec->name;
        if (min_out)
            *min_out = spec->min_value;
        if (max_out)
            *max_out = spec->max_value;
        if (default_out)
            *default_out = spec->default_value;
        if (is_integer_out)
            *is_integer_out = spec->is_integer ? 1 : 0;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_option_choice_at(flt_option key, size_t index,
                                                 const char **name_out, int *value_out) {
    const char *fn = "flt_option_choice_at";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, name_out);
        const option_spec *spec = enum_arg(key) < 0 ? nullptr : find_option(key);
        if (!spec)
            return unknown_key(fn, enum_arg(key));
        std::size_t seen = 0;
        for (const option_choice &choice : k_choices) {
            if (choice.key != key)
                continue;
            if (seen++ == index) {
                *name_out = choice.name;
                if (value_out)
                    *value_out = choice.value;
                return FLT_OK;
            }
        }
        if (seen == 0)
            return fail(FLT_ERR_NOT_FOUND, "%s: option '%s' is a number, not a choice", fn,
                        spec->name);
        return fail(FLT_ERR_NOT_FOUND, "%s: index %zu is past the last of the %zu choices of '%s'",
                    fn, index, seen, spec->name);
    });
}

FLT_API flt_status FLT_CALL flt_option_at(size_t index, flt_option *out) {
    const char *fn = "flt_option_at";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        if (index >= k_option_count)
            return fail(FLT_ERR_NOT_FOUND, "%s: index %zu is past the last of %zu options", fn,
                        index, k_option_count);
        *out = k_options[index].key;
        return FLT_OK;
    });
}

}  // extern "C"
