// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;

namespace Flatline
{
    /// <summary>One option key of the C library: its name, inclusive bounds,
    /// default, and whether it takes whole numbers only.</summary>
    public sealed class OptionInfo
    {
        internal OptionInfo(string name, double min, double max, double defaultValue, bool isInteger,
                            IReadOnlyDictionary<string, int> choices)
        {
            Name = name;
            Min = min;
            Max = max;
            Default = defaultValue;
            IsInteger = isInteger;
            Choices = choices;
        }

        public string Name { get; }
        public double Min { get; }
        public double Max { get; }
        public double Default { get; }
        public bool IsInteger { get; }
        /// <summary>For an option whose value is a choice, the C library's
        /// name of each value (e.g. "huber" = 1, the value of
        /// <see cref="RobustMode.Huber"/>); empty for a number.</summary>
        public IReadOnlyDictionary<string, int> Choices { get; }
        // Invariant: the same text under every culture, as the C library writes numbers.
        public override string ToString() =>
            FormattableString.Invariant($"{Name} [{Min}, {Max}] default {Default}{(IsInteger ? " (integer)" : "")}");
    }

    /// <summary>
    /// A bag of option values (flt_options). Keys are set by their C name
    /// ("knot_spacing", ...) through flt_option_find, so an option added to
    /// the C library is usable here without a binding change; the typed
    /// properties cover the options known when this binding was written
    /// (calibration, simulator, extractor, flatness, frame-source and gauge
    /// keys carry a Calib / Sim / Extract / Flat / Source or U3v / Gauge
    /// prefix).
    /// Keys never set keep their default. Objects created from a bag keep
    /// their own copy of the values, so the bag may be disposed right after.
    /// </summary>
    public sealed class FlatlineOptions : IDisposable
    {
        private readonly OptionsHandle handle;

        static FlatlineOptions() => NativeLoader.EnsureLoaded();

        /// <summary>A bag holding every default.</summary>
        public FlatlineOptions()
        {
            FlatlineNative.flt_options_create(out handle);
            handle.Track(0);
        }

        /// <summary>A bag the library made (a recording's options).</summary>
        internal FlatlineOptions(OptionsHandle made)
        {
            handle = made;
            handle.Track(0);
        }

        /// <summary>Every option key the native library knows, in its order.</summary>
        public static IReadOnlyList<OptionInfo> Available
        {
            get
            {
                NativeLoader.EnsureLoaded();
                var keys = new List<OptionInfo>();
                for (ulong index = 0; ; ++index)
                {
                    int key;
                    try
                    {
                        FlatlineNative.flt_option_at(index, out key);
                    }
                    catch (NotFoundException)
                    {
                        break;  // past the last key
                    }
                    keys.Add(Info(key));
                }
                return keys;
            }
        }

        /// <summary>Describes one option by name; <see cref="NotFoundException"/>
        /// if the library has no such option.</summary>
        public static OptionInfo Describe(string name) => Info(Key(name));

        /// <summary>The value of an option by its C name.</summary>
        public double this[string name]
        {
            get => Get(name);
            set => Set(name, value);
        }

        /// <summary>Sets an option by its C name. <see cref="NotFoundException"/>
        /// for an unknown name; <see cref="InvalidArgumentException"/> for a
        /// NaN, a value outside the bounds or a fraction for an integer option
        /// (the bag is then unchanged).</summary>
        public FlatlineOptions Set(string name, double value)
        {
            int key = Key(name);
            FlatlineNative.flt_options_set(LiveHandle, key, value);
            return this;
        }

        /// <summary>Reads an option by its C name (its default if never set).</summary>
        public double Get(string name)
        {
            int key = Key(name);
            FlatlineNative.flt_options_get(LiveHandle, key, out double value);
            return value;
        }

        /// <summary>Distance L between spline knots along travel, mm; 0 means
        /// "equal to LaserSpacing".</summary>
        public double KnotSpacing { get => Get("knot_spacing"); set => Set("knot_spacing", value); }
        /// <summary>Distance between the two laser lines along travel, mm.</summary>
        public double LaserSpacing { get => Get("laser_spacing"); set => Set("laser_spacing", value); }
        /// <summary>Standard deviation of one measured height, mm.</summary>
        public double HeightSigma { get => Get("height_sigma"); set => Set("height_sigma", value); }
        /// <summary>Standard deviation of one measured slope, mm/mm.</summary>
        public double SlopeSigma { get => Get("slope_sigma"); set => Set("slope_sigma", value); }
        /// <summary>Weight of the smoothness prior relative to one height sample.</summary>
        public double CurvatureWeight { get => Get("curvature_weight"); set => Set("curvature_weight", value); }
        /// <summary>Weight of the prior against jumps of the curvature at the
        /// knots, relative to one height sample: it removes the wiggle the
        /// secant slopes cannot see.</summary>
        public double CurvatureJumpWeight { get => Get("curvature_jump_weight"); set => Set("curvature_jump_weight", value); }
        /// <summary>Knots beyond a knot that must be complete before the
        /// streaming reconstructor emits it; -1 (the default) derives it from
        /// <see cref="LatencyMm"/>. Set one of the two.</summary>
        public int LagKnots { get => (int)Get("lag_knots"); set => Set("lag_knots", value); }
        /// <summary>The most strip (mm) the streaming reconstructor takes
        /// beyond a row before the row is final (twice that at a strip's
        /// head); default 2000. docs/reconstruction.md tables its price.</summary>
        public double LatencyMm { get => Get("latency_mm"); set => Set("latency_mm", value); }
        /// <summary>Runs of invalid samples whose valid neighbours are further
        /// apart than this are flagged Gap, mm.</summary>
        public double MaxGap { get => Get("max_gap"); set => Set("max_gap", value); }
        /// <summary>Rows the streaming reconstructor can hold (9 bytes per
        /// row and fiber).</summary>
        public int RowCapacity { get => (int)Get("row_capacity"); set => Set("row_capacity", value); }
        /// <summary>Model the vibration as a rigid heave and roll of each
        /// frame (one line across the strip) and take it out of the fibers'
        /// shape; see the C header for the trade-offs.</summary>
        public bool RigidMotion { get => Get("rigid_motion") != 0; set => Set("rigid_motion", value ? 1 : 0); }
        /// <summary>With RigidMotion, standard deviation of a height's
        /// deviation from its frame's line across the strip, mm.</summary>
        public double ShapeSigma { get => Get("shape_sigma"); set => Set("shape_sigma", value); }
        /// <summary>Robust reconstruction (<see cref="RobustMode"/>): takes
        /// outliers such as the shear station's ringing and spurious laser
        /// peaks out, noise levels estimated from the data.</summary>
        public RobustMode Robust { get => (RobustMode)(int)Get("robust"); set => Set("robust", (int)value); }
        /// <summary>Reweighted passes over the fibers after the plain one (1..10).</summary>
        public int RobustIterations { get => (int)Get("robust_iterations"); set => Set("robust_iterations", value); }
        /// <summary>With RigidMotion and Robust, reweighted passes over the
        /// line across the strip, which carries the shear station's ringing
        /// (1..32).</summary>
        public int RobustLineIterations { get => (int)Get("robust_line_iterations"); set => Set("robust_line_iterations", value); }

        // ---- calibration (Calibration.EstimateIntrinsics / EstimateHomography)
        /// <summary>Estimate the homographies inside RANSAC.</summary>
        public bool CalibRansac { get => Get("calib_ransac") != 0; set => Set("calib_ransac", value ? 1 : 0); }
        /// <summary>RANSAC inlier threshold: image reprojection distance, px.</summary>
        public double CalibRansacThreshold { get => Get("calib_ransac_threshold"); set => Set("calib_ransac_threshold", value); }
        /// <summary>RANSAC iterations.</summary>
        public int CalibRansacIterations { get => (int)Get("calib_ransac_iterations"); set => Set("calib_ransac_iterations", value); }
        /// <summary>Seed of RANSAC's draws (the estimate is deterministic).</summary>
        public uint CalibRansacSeed { get => (uint)Get("calib_ransac_seed"); set => Set("calib_ransac_seed", value); }
        /// <summary>Estimate the rational distortion terms k4..k6 too.</summary>
        public bool CalibRationalDistortion { get => Get("calib_rational_distortion") != 0; set => Set("calib_rational_distortion", value ? 1 : 0); }

        // ---- simulated sensor (SimulatedLine); flatline/sim.h has the model
        /// <summary>Seed of every random draw: same seed, same output.</summary>
        public uint SimSeed { get => (uint)Get("sim_seed"); set => Set("sim_seed", value); }
        /// <summary>Travel between frames, mm.</summary>
        public double SimFrameSpacing { get => Get("sim_frame_spacing"); set => Set("sim_frame_spacing", value); }
        /// <summary>Encoder position of frame 0, mm.</summary>
        public double SimStart { get => Get("sim_start"); set => Set("sim_start", value); }
        /// <summary>Strip width W, mm (the defect shapes span [-W/2, W/2]).</summary>
        public double SimStripWidth { get => Get("sim_strip_width"); set => Set("sim_strip_width", value); }
        /// <summary>Standard deviation of the rigid heave per frame, mm.</summary>
        public double SimHeaveSigma { get => Get("sim_heave_sigma"); set => Set("sim_heave_sigma", value); }
        /// <summary>Standard deviation of the roll about the travel axis per frame, mm/mm.</summary>
        public double SimTiltSigma { get => Get("sim_tilt_sigma"); set => Set("sim_tilt_sigma", value); }
        /// <summary>Amplitude of a leveler roll's run-out, mm.</summary>
        public double SimEccentricityAmplitude { get => Get("sim_eccentricity_amplitude"); set => Set("sim_eccentricity_amplitude", value); }
        /// <summary>Period of the run-out along the encoder, mm.</summary>
        public double SimEccentricityPeriod { get => Get("sim_eccentricity_period"); set => Set("sim_eccentricity_period", value); }
        /// <summary>Amplitude of the shear transient at every cut, mm.</summary>
        public double SimShearAmplitude { get => Get("sim_shear_amplitude"); set => Set("sim_shear_amplitude", value); }
        /// <summary>Decay of the shear transient, 1/mm.</summary>
        public double SimShearDecay { get => Get("sim_shear_decay"); set => Set("sim_shear_decay", value); }
        /// <summary>Period of the shear transient, mm.</summary>
        public double SimShearPeriod { get => Get("sim_shear_period"); set => Set("sim_shear_period", value); }
        /// <summary>Distance between cuts, mm.</summary>
        public double SimShearInterval { get => Get("sim_shear_interval"); set => Set("sim_shear_interval", value); }
        /// <summary>Peak-detection noise, px, per laser and fiber (rows) or column (frames).</summary>
        public double SimPeakSigma { get => Get("sim_peak_sigma"); set => Set("sim_peak_sigma", value); }
        /// <summary>Bits per pixel of the rendered frames: 8, 10, 12 or 16.</summary>
        public int SimBitDepth { get => (int)Get("sim_bit_depth"); set => Set("sim_bit_depth", value); }
        /// <summary>Standard deviation of the line's profile across rows, px.</summary>
        public double SimLineSigma { get => Get("sim_line_sigma"); set => Set("sim_line_sigma", value); }
        /// <summary>Peak of the line, fraction of full scale.</summary>
        public double SimLinePeak { get => Get("sim_line_peak"); set => Set("sim_line_peak", value); }
        /// <summary>Background, fraction of full scale.</summary>
        public double SimBackground { get => Get("sim_background"); set => Set("sim_background", value); }
        /// <summary>Speckle contrast (multiplicative per pixel).</summary>
        public double SimSpeckle { get => Get("sim_speckle"); set => Set("sim_speckle", value); }
        /// <summary>Electrons at full scale (shot noise); 0 for none.</summary>
        public double SimFullWell { get => Get("sim_full_well"); set => Set("sim_full_well", value); }
        /// <summary>Spurious reflections per frame.</summary>
        public double SimReflections { get => Get("sim_reflections"); set => Set("sim_reflections", value); }
        /// <summary>What the lasers fall on beyond the strip's edges.</summary>
        public SimSurround SimSurround { get => (SimSurround)(int)Get("sim_surround"); set => Set("sim_surround", (int)value); }
        /// <summary>Mean lateral position of the strip's centre line, sensor x, mm.</summary>
        public double SimStripOffset { get => Get("sim_strip_offset"); set => Set("sim_strip_offset", value); }
        /// <summary>Amplitude of the sine in the strip's lateral wander, mm.</summary>
        public double SimWanderAmplitude { get => Get("sim_wander_amplitude"); set => Set("sim_wander_amplitude", value); }
        /// <summary>Its period in encoder travel, mm.</summary>
        public double SimWanderPeriod { get => Get("sim_wander_period"); set => Set("sim_wander_period", value); }
        /// <summary>Standard deviation of the wander's slow random walk, mm.</summary>
        public double SimWanderSigma { get => Get("sim_wander_sigma"); set => Set("sim_wander_sigma", value); }
        /// <summary>Length of each coil along travel, mm; 0 for one endless strip.</summary>
        public double SimCoilLength { get => Get("sim_coil_length"); set => Set("sim_coil_length", value); }
        /// <summary>Travel between one coil's tail and the next one's head, mm.</summary>
        public double SimCoilGap { get => Get("sim_coil_gap"); set => Set("sim_coil_gap", value); }
        /// <summary>Width of every second coil, mm; 0 for SimStripWidth.</summary>
        public double SimSecondWidth { get => Get("sim_second_width"); set => Set("sim_second_width", value); }
        /// <summary>Share of the charge above full scale that blooms into the neighbouring rows.</summary>
        public double SimBlooming { get => Get("sim_blooming"); set => Set("sim_blooming", value); }
        /// <summary>Probability of a glint at each strip edge, per laser and frame.</summary>
        public double SimEdgeGlints { get => Get("sim_edge_glints"); set => Set("sim_edge_glints", value); }
        /// <summary>Height from the focal plane (z = 0) at which the line has widened by sqrt(2), mm; 0 for always in focus.</summary>
        public double SimDepthOfField { get => Get("sim_depth_of_field"); set => Set("sim_depth_of_field", value); }
        /// <summary>Share of the strip's surface under dark patches (0.15-0.5 of the line's light), 0..1.</summary>
        public double SimDarkPatches { get => Get("sim_dark_patches"); set => Set("sim_dark_patches", value); }
        /// <summary>The camera's gamma: a pixel reads full scale times (signal / full scale)^(1 / gamma).</summary>
        public double SimGamma { get => Get("sim_gamma"); set => Set("sim_gamma", value); }
        /// <summary>Ambient light on bare steel around the lines, fraction of full scale; 0 for a dark strip.</summary>
        public double SimAmbient { get => Get("sim_ambient"); set => Set("sim_ambient", value); }
        /// <summary>Contrast of the strip's 2 mm texture cells, 0..1 (line and ambient light alike).</summary>
        public double SimTexture { get => Get("sim_texture"); set => Set("sim_texture", value); }

        // ---- frame-to-profile extractor (Extractor); flatline/extractor.h
        /// <summary>First frame row of laser 0's band, px.</summary>
        public int ExtractLaser0FirstRow { get => (int)Get("extract_laser0_first_row"); set => Set("extract_laser0_first_row", value); }
        /// <summary>Rows of laser 0's band; 0 (with laser 1's also 0) for
        /// automatic bands found in the first frame.</summary>
        public int ExtractLaser0Rows { get => (int)Get("extract_laser0_rows"); set => Set("extract_laser0_rows", value); }
        /// <summary>First frame row of laser 1's band, px.</summary>
        public int ExtractLaser1FirstRow { get => (int)Get("extract_laser1_first_row"); set => Set("extract_laser1_first_row", value); }
        /// <summary>Rows of laser 1's band (0: automatic).</summary>
        public int ExtractLaser1Rows { get => (int)Get("extract_laser1_rows"); set => Set("extract_laser1_rows", value); }
        /// <summary>Savitzky-Golay window, rows, odd.</summary>
        public int ExtractSgWindow { get => (int)Get("extract_sg_window"); set => Set("extract_sg_window", value); }
        /// <summary>Savitzky-Golay polynomial order.</summary>
        public int ExtractSgOrder { get => (int)Get("extract_sg_order"); set => Set("extract_sg_order", value); }
        /// <summary>Weakest accepted peak, fraction of full scale.</summary>
        public double ExtractMinPeak { get => Get("extract_min_peak"); set => Set("extract_min_peak", value); }
        /// <summary>Widest accepted line: rows at or above half its maximum.</summary>
        public double ExtractMaxWidth { get => Get("extract_max_width"); set => Set("extract_max_width", value); }
        /// <summary>A line lower than this is not on the strip (the roller table), mm.</summary>
        public double ExtractStripMinZ { get => Get("extract_strip_min_z"); set => Set("extract_strip_min_z", value); }
        /// <summary>Widest dark stretch across the strip not taken for its end, mm.</summary>
        public double ExtractEdgeGap { get => Get("extract_edge_gap"); set => Set("extract_edge_gap", value); }
        /// <summary>Narrowest run of line taken for the strip, mm.</summary>
        public double ExtractMinStripWidth { get => Get("extract_min_strip_width"); set => Set("extract_min_strip_width", value); }

        // ---- flatness metrics (Flatness); flatline/flatness.h
        /// <summary>Streamed evaluation window: the last N mm of strip; 0 for
        /// no automatic windows (only Finish evaluates, one window per sheet).</summary>
        public double FlatWindowLength { get => Get("flat_window_length"); set => Set("flat_window_length", value); }
        /// <summary>Strip between two streamed evaluations, mm, at most
        /// FlatWindowLength; 0 = FlatWindowLength (windows side by side).</summary>
        public double FlatUpdateInterval { get => Get("flat_update_interval"); set => Set("flat_update_interval", value); }
        /// <summary>Width of an I-Unit zone across the strip, mm.</summary>
        public double FlatZoneWidth { get => Get("flat_zone_width"); set => Set("flat_zone_width", value); }
        /// <summary>The I-Unit reference length (<see cref="Flatline.FlatReference"/>):
        /// the shortest valid fiber (the default) or the mean of the valid fibers.</summary>
        public FlatReference FlatReference { get => (FlatReference)(int)Get("flat_reference"); set => Set("flat_reference", (int)value); }
        /// <summary>Shortest window the metrics accept, mm (one flatness wave).</summary>
        public double FlatMinLength { get => Get("flat_min_length"); set => Set("flat_min_length", value); }
        /// <summary>Least share of a window (0..1) a fiber's usable rows must cover.</summary>
        public double FlatMinCoverage { get => Get("flat_min_coverage"); set => Set("flat_min_coverage", value); }
        /// <summary>A crest or trough counts once the profile has retreated
        /// from it by this much, mm.</summary>
        public double FlatWaveHysteresis { get => Get("flat_wave_hysteresis"); set => Set("flat_wave_hysteresis", value); }
        /// <summary>A window whose zone profile spans less than this is flat, I-Units.</summary>
        public double FlatFlatLimit { get => Get("flat_flat_limit"); set => Set("flat_flat_limit", value); }
        /// <summary>|Bow| from which ShapeComponents.Bow is set, mm of sagitta over the window.</summary>
        public double FlatBowLimit { get => Get("flat_bow_limit"); set => Set("flat_bow_limit", value); }
        /// <summary>|Crossbow| from which ShapeComponents.Crossbow is set, mm of sagitta over the width.</summary>
        public double FlatCrossbowLimit { get => Get("flat_crossbow_limit"); set => Set("flat_crossbow_limit", value); }
        /// <summary>Rows one streamed window (or sheet) may hold (9 bytes per row and fiber).</summary>
        public int FlatRowCapacity { get => (int)Get("flat_row_capacity"); set => Set("flat_row_capacity", value); }
        /// <summary>Zones across the strip, each an equal share of its width; 0 for zones of FlatZoneWidth.</summary>
        public int FlatZoneCount { get => (int)Get("flat_zone_count"); set => Set("flat_zone_count", value); }
        /// <summary>The sensor side of the leveler's drive side.</summary>
        public DriveSide FlatDriveSide { get => (DriveSide)(int)Get("flat_drive_side"); set => Set("flat_drive_side", (int)value); }
        /// <summary>Where zones are laid: on the strip (the default) or on the fiber grid.</summary>
        public ZonesOn FlatZonesOn { get => (ZonesOn)(int)Get("flat_zones_on"); set => Set("flat_zones_on", (int)value); }

        // ---- frame sources (FrameSource); flatline/source.h
        /// <summary>Where a frame's encoder position comes from.</summary>
        public EncoderMode SourceEncoderMode { get => (EncoderMode)(int)Get("source_encoder_mode"); set => Set("source_encoder_mode", (int)value); }
        /// <summary>Travel per frame (per block id) in fixed-step mode, mm.</summary>
        public double SourceEncoderStep { get => Get("source_encoder_step"); set => Set("source_encoder_step", value); }
        /// <summary>Encoder position of the first frame (fixed step) or of
        /// count 0 (chunk counter), mm.</summary>
        public double SourceEncoderStart { get => Get("source_encoder_start"); set => Set("source_encoder_start", value); }
        /// <summary>Travel per encoder count of a chunk counter, mm.</summary>
        public double SourceEncoderMmPerCount { get => Get("source_encoder_mm_per_count"); set => Set("source_encoder_mm_per_count", value); }
        /// <summary>The chunk id of the camera's encoder counter (see its XML's ChunkID).</summary>
        public uint SourceEncoderChunkId { get => (uint)Get("source_encoder_chunk_id"); set => Set("source_encoder_chunk_id", value); }
        /// <summary>Significant bits of 16-bit image files: 0 = Mono16, or 10 or 12.</summary>
        public int SourceImageBits { get => (int)Get("source_image_bits"); set => Set("source_image_bits", value); }
        /// <summary>Asynchronous USB bulk transfers kept in flight.</summary>
        public int U3vTransfers { get => (int)Get("u3v_transfers"); set => Set("u3v_transfers", value); }
        /// <summary>Largest payload transfer, bytes (rounded down to the camera's alignment).</summary>
        public int U3vTransferSize { get => (int)Get("u3v_transfer_size"); set => Set("u3v_transfer_size", value); }
        /// <summary>Floor of the control channel timeout, ms.</summary>
        public int U3vControlTimeout { get => (int)Get("u3v_control_timeout"); set => Set("u3v_control_timeout", value); }
        /// <summary>Pending acknowledges accepted for one command before giving up.</summary>
        public int U3vPendingAckLimit { get => (int)Get("u3v_pending_ack_limit"); set => Set("u3v_pending_ack_limit", value); }
        /// <summary>Times a command is sent when no acknowledge comes.</summary>
        public int U3vCommandAttempts { get => (int)Get("u3v_command_attempts"); set => Set("u3v_command_attempts", value); }
        /// <summary>GigE Vision stream packet size, bytes (IP + UDP + GVSP headers + data); 0 negotiates it.</summary>
        public int GigePacketSize { get => (int)Get("gige_packet_size"); set => Set("gige_packet_size", value); }
        /// <summary>Wait for a GVCP acknowledge, ms.</summary>
        public int GigeControlTimeout { get => (int)Get("gige_control_timeout"); set => Set("gige_control_timeout", value); }
        /// <summary>Times a GVCP command is sent when no acknowledge comes.</summary>
        public int GigeCommandAttempts { get => (int)Get("gige_command_attempts"); set => Set("gige_command_attempts", value); }
        /// <summary>The camera drops our control after this long without a heartbeat, ms.</summary>
        public int GigeHeartbeatTimeout { get => (int)Get("gige_heartbeat_timeout"); set => Set("gige_heartbeat_timeout", value); }
        /// <summary>Times a lost packet is asked again before its frame is dropped (0: never).</summary>
        public int GigeResendAttempts { get => (int)Get("gige_resend_attempts"); set => Set("gige_resend_attempts", value); }
        /// <summary>Wait for a packet asked again before asking once more, ms.</summary>
        public int GigeResendTimeout { get => (int)Get("gige_resend_timeout"); set => Set("gige_resend_timeout", value); }
        /// <summary>Receive buffer asked for the stream socket, bytes.</summary>
        public int GigeSocketBuffer { get => (int)Get("gige_socket_buffer"); set => Set("gige_socket_buffer", value); }
        /// <summary>How long opening by serial or name waits for discovery answers, ms.</summary>
        public int GigeDiscoveryTimeout { get => (int)Get("gige_discovery_timeout"); set => Set("gige_discovery_timeout", value); }
        /// <summary>Frames assembled at once while lost packets are asked again.</summary>
        public int GigeAssemblyFrames { get => (int)Get("gige_assembly_frames"); set => Set("gige_assembly_frames", value); }

        // ---- the gauge (Gauge); flatline/gauge.h
        /// <summary>Threads that process the frames; 0 processes each frame on
        /// the thread that delivers it.</summary>
        public int GaugeWorkers { get => (int)Get("gauge_workers"); set => Set("gauge_workers", value); }
        /// <summary>Frames the queue between acquisition and processing holds
        /// (width x height x 2 bytes each); 0 (the default) for as many as fit
        /// in 256 MiB, at least 16.</summary>
        public int GaugeQueueFrames { get => (int)Get("gauge_queue_frames"); set => Set("gauge_queue_frames", value); }
        /// <summary>What a full frame queue does (<see cref="Flatline.GaugeOverflow"/>,
        /// gauge_overflow): by default the pushing thread waits for room and
        /// an attached camera drops (counted and flagged on its sheet).</summary>
        public GaugeOverflow GaugeOverflow { get => (GaugeOverflow)(int)Get("gauge_overflow"); set => Set("gauge_overflow", (int)value); }
        /// <summary>The least encoder advance for a frame to be taken, mm
        /// (closer frames are a line stop); sizes the buffers.</summary>
        public double GaugeFrameSpacing { get => Get("gauge_frame_spacing"); set => Set("gauge_frame_spacing", value); }
        /// <summary>A reversal longer than this, mm, starts a new strip.</summary>
        public double GaugeReversalLength { get => Get("gauge_reversal_length"); set => Set("gauge_reversal_length", value); }
        /// <summary>A frame shows the strip when its valid fibers span this, mm.</summary>
        public double GaugeStripMinWidth { get => Get("gauge_strip_min_width"); set => Set("gauge_strip_min_width", value); }
        /// <summary>The strip has left when no frame showed it over this, mm.</summary>
        public double GaugeTailLength { get => Get("gauge_tail_length"); set => Set("gauge_tail_length", value); }
        /// <summary>A sheet this long without a cut is ended there, mm.</summary>
        public double GaugeMaxSheetLength { get => Get("gauge_max_sheet_length"); set => Set("gauge_max_sheet_length", value); }
        /// <summary>What each sheet keeps: 0 nothing, 1 its reconstructed
        /// height map, 2 also the measured heights.</summary>
        public int GaugeKeepMaps { get => (int)Get("gauge_keep_maps"); set => Set("gauge_keep_maps", value); }
        /// <summary>Sheets made at create time, which waiting and held sheets
        /// use without allocating.</summary>
        public int GaugeSheetSlots { get => (int)Get("gauge_sheet_slots"); set => Set("gauge_sheet_slots", value); }
        /// <summary>A sheet whose rows measured are less than this share of
        /// the rows its length should hold is incomplete and not judged
        /// (0..1, default 0.95).</summary>
        public double GaugeMinCoverage { get => Get("gauge_min_coverage"); set => Set("gauge_min_coverage", value); }
        /// <summary>Sheets that may exist beyond <see cref="GaugeSheetSlots"/>
        /// before pushes are refused (<see cref="BufferFullException"/>); 0
        /// drops the oldest waiting sheet instead.</summary>
        public int GaugeSheetBacklog { get => (int)Get("gauge_sheet_backlog"); set => Set("gauge_sheet_backlog", value); }
        /// <summary>A sheet whose share of saturated laser peaks exceeds this
        /// is logged as overexposed (0..1).</summary>
        public double GaugeSaturationLimit { get => Get("gauge_saturation_limit"); set => Set("gauge_saturation_limit", value); }
        /// <summary>Once the strip is this far past a cut (mm), the open
        /// sheet's provisional result (<see cref="SheetFlags.Provisional"/>);
        /// its final follows. 0 (the default): none.</summary>
        public double GaugeProvisionalMm { get => Get("gauge_provisional_mm"); set => Set("gauge_provisional_mm", value); }

        // ---- the leveler advisor (Advisor); flatline/advisor.h
        /// <summary>Lambda of the advice relative to the mean squared effect of
        /// a unit step (advisor_damping).</summary>
        public double AdvisorDamping { get => Get("advisor_damping"); set => Set("advisor_damping", value); }
        /// <summary>The share of the expected deviation one advice sets out to
        /// remove, 0.01..1 (advisor_gain).</summary>
        public double AdvisorGain { get => Get("advisor_gain"); set => Set("advisor_gain", value); }

        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }

        internal OptionsHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(FlatlineOptions));
                return handle;
            }
        }

        internal static int Key(string name)
        {
            if (name == null)
                throw new ArgumentNullException(nameof(name));
            FlatlineNative.flt_option_find(name, out int key);
            return key;
        }

        private static OptionInfo Info(int key)
        {
            FlatlineNative.flt_option_info(key, out IntPtr name, out double min, out double max,
                                           out double defaultValue, out int isInteger);
            var choices = new Dictionary<string, int>();
            // Only whole-number options can be choices; the library names
            // their values until NotFound.
            for (ulong index = 0; isInteger != 0; ++index)
            {
                try
                {
                    FlatlineNative.flt_option_choice_at(key, index, out IntPtr choice, out int value);
                    choices.Add(Utf8.Decode(choice), value);
                }
                catch (NotFoundException)
                {
                    break;  // past the last choice, or a number
                }
            }
            return new OptionInfo(Utf8.Decode(name), min, max, defaultValue, isInteger != 0, choices);
        }

        /// <summary>The caller's bag, or a bag of defaults for null (the
        /// marshaller cannot pass a null SafeHandle), disposed with the scope.</summary>
        internal static Scope Borrow(FlatlineOptions? options) =>
            options != null ? new Scope(options.LiveHandle, null) : Defaults(new FlatlineOptions());

        private static Scope Defaults(FlatlineOptions defaults) => new Scope(defaults.handle, defaults);

        internal readonly struct Scope : IDisposable
        {
            private readonly FlatlineOptions? owned;
            /// <summary>The handle to pass; <paramref name="owned"/>: the
            /// bag of defaults it belongs to, disposed with the scope (null
            /// for the caller's bag).</summary>
            internal Scope(OptionsHandle handle, FlatlineOptions? owned)
            {
                Handle = handle;
                this.owned = owned;
            }
            internal OptionsHandle Handle { get; }
            public void Dispose() => owned?.Dispose();
        }
    }
}
