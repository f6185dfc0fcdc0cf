// SPDX-License-Identifier: Apache-2.0
using System;

namespace Flatline
{
    /// <summary>
    /// Parametric defects of the simulated sheet (flt_sim_defect in
    /// flatline/sim.h). Each is amplitude * g(x) * w(s) with
    /// w(s) = sin(2 pi s / period) (1 for period 0) and, with W the strip
    /// width and x in [-W/2, W/2]:
    /// </summary>
    public enum DefectKind
    {
        /// <summary>g = 0.</summary>
        Flat = NativeDefect.FLT_SIM_FLAT,
        /// <summary>g = cos^2(pi x / W): long centre, flat edges.</summary>
        CentreBuckle = NativeDefect.FLT_SIM_CENTRE_BUCKLE,
        /// <summary>g = (max(0, -2x/W))^4: x &lt; 0 is the left edge.</summary>
        WavyEdgeLeft = NativeDefect.FLT_SIM_WAVY_EDGE_LEFT,
        /// <summary>g = (max(0, 2x/W))^4.</summary>
        WavyEdgeRight = NativeDefect.FLT_SIM_WAVY_EDGE_RIGHT,
        /// <summary>g = (2x/W)^4.</summary>
        WavyEdgeBoth = NativeDefect.FLT_SIM_WAVY_EDGE_BOTH,
        /// <summary>g = exp(-((|x| - W/4) / (W/8))^2).</summary>
        QuarterBuckle = NativeDefect.FLT_SIM_QUARTER_BUCKLE,
        /// <summary>g = 1: coil set, the whole width together.</summary>
        Bow = NativeDefect.FLT_SIM_BOW,
        /// <summary>g = (2x/W)^2 (period 0: a constant transverse bow).</summary>
        Crossbow = NativeDefect.FLT_SIM_CROSSBOW,
    }

    /// <summary>What the lasers fall on beyond the strip's edges (the option
    /// "sim_surround", flt_sim_surround in flatline/sim.h).</summary>
    public enum SimSurround
    {
        /// <summary>The strip fills the field of view (the default).</summary>
        Strip = NativeSimSurround.FLT_SIM_SURROUND_STRIP,
        /// <summary>Nothing: no line beyond the edges or between coils.</summary>
        Nothing = NativeSimSurround.FLT_SIM_SURROUND_NOTHING,
        /// <summary>The roller table, SimTableDepth below the pass line.</summary>
        RollerTable = NativeSimSurround.FLT_SIM_SURROUND_ROLLER_TABLE,
    }

    /// <summary>The simulated strip's edges (<see cref="SimulatedLine.StripEdges"/>):
    /// sensor x, mm, [positions]; NaN where <see cref="Present"/> is false.</summary>
    public sealed class SimulatedEdges
    {
        internal SimulatedEdges(double[] leftMm, double[] rightMm, bool[] present)
        {
            LeftMm = leftMm;
            RightMm = rightMm;
            Present = present;
        }

        /// <summary>The edge at low sensor x, mm.</summary>
        public double[] LeftMm { get; }
        /// <summary>The edge at high sensor x, mm.</summary>
        public double[] RightMm { get; }
        /// <summary>True where the laser (or both, for the row) sees the strip.</summary>
        public bool[] Present { get; }
    }

    /// <summary>
    /// Profile rows from <see cref="SimulatedLine.NextRows"/>: what the
    /// extractor would produce, with the ground truth. Arrays per row are
    /// [rows]; per sample [rows, fibers] (rows along travel, fibers across
    /// the width), ready for <see cref="Reconstructor.Push(double[], double[,], double[,], bool[,])"/>.
    /// </summary>
    public sealed class SimulatedRows
    {
        internal SimulatedRows(double[] encoderMm, double[] s, double[,] height, double[,] slope,
                               bool[,] valid, double[,] truth)
        {
            EncoderMm = encoderMm;
            S = s;
            Height = height;
            Slope = slope;
            Valid = valid;
            Truth = truth;
        }

        /// <summary>Each frame's encoder position, mm.</summary>
        public double[] EncoderMm { get; }
        /// <summary>Each row's material position, mm: the encoder position
        /// minus the mean of the two laser offsets.</summary>
        public double[] S { get; }
        /// <summary>Mean of the two lasers' heights, mm.</summary>
        public double[,] Height { get; }
        /// <summary>Secant slope between the two lasers, mm/mm.</summary>
        public double[,] Slope { get; }
        /// <summary>Validity per sample (the simulator's rows are all valid).</summary>
        public bool[,] Valid { get; }
        /// <summary>The sheet's true height at (x of the fiber, S of the row), mm.</summary>
        public double[,] Truth { get; }
        public int Rows => S.Length;
        public int Fibers => Height.GetLength(1);
    }

    /// <summary>
    /// A rendered camera frame from <see cref="SimulatedLine.NextFrame()"/>.
    /// Exactly one of <see cref="Pixels8"/> (Mono8) and <see cref="Pixels16"/>
    /// (Mono10/12/16) is set, by <see cref="Format"/>; both are
    /// [height, width] (rows, columns), row-major like the camera's buffer.
    /// </summary>
    public sealed class SimulatedFrame
    {
        internal SimulatedFrame(PixelFormat format, Array pixels, double encoderMm,
                                double[] truth, double[,] peakRows)
        {
            Format = format;
            Pixels = pixels;
            EncoderMm = encoderMm;
            Truth = truth;
            PeakRows = peakRows;
        }

        public PixelFormat Format { get; }
        /// <summary>The pixels of a Mono8 frame, else null.</summary>
        public byte[,]? Pixels8 => Pixels as byte[,];
        /// <summary>The pixels of a Mono10, Mono12 or Mono16 frame, else null.</summary>
        public ushort[,]? Pixels16 => Pixels as ushort[,];
        /// <summary>The pixels whatever the format: a byte[,] or a ushort[,].</summary>
        public Array Pixels { get; }
        public int Width => Pixels.GetLength(1);
        public int Height => Pixels.GetLength(0);
        /// <summary>The frame's encoder position, mm.</summary>
        public double EncoderMm { get; }
        /// <summary>[fibers] the sheet's true height at the frame's row position, mm.</summary>
        public double[] Truth { get; }
        /// <summary>[2, width]: per laser and column the exact row of the line
        /// centre (after the peak noise), px; NaN where the line is outside
        /// the frame.</summary>
        public double[,] PeakRows { get; }
    }

    /// <summary>
    /// The simulated sensor (flt_sim): a sheet made of parametric defects and
    /// an optional height map, seen by the dual-line-laser sensor of a
    /// <see cref="Calibration"/>, with rigid motion, shear transients and
    /// peak noise (FlatlineOptions' Sim* keys). <see cref="NextRows"/> gives
    /// profile rows without a camera; <see cref="NextFrame()"/> renders
    /// camera frames through the calibration. Both advance the same frame
    /// counter and carry the ground truth. Deterministic: the same seed and
    /// calls give the same bytes. See include/flatline/sim.h for the model.
    /// </summary>
    /// <remarks>
    /// Holds its <see cref="Calibration"/> (the GC cannot collect it while the
    /// line lives; the native simulator copied it at creation, so even a
    /// disposed calibration does not stop the line). Not thread-safe: one
    /// thread at a time; separate lines are independent.
    /// </remarks>
    public sealed class SimulatedLine : IDisposable
    {
        private readonly SimHandle handle;
        private readonly bool ownsCalibration;

        static SimulatedLine() => NativeLoader.EnsureLoaded();

        /// <summary>
        /// A simulator of the sensor described by <paramref name="calibration"/>
        /// (finished, else <see cref="FlatlineStateException"/>), or of the
        /// reference sensor (<see cref="Calibration.Reference"/> with its
        /// defaults: 2048 x 2048 px, 1001 fibers every 2 mm) when null.
        /// <paramref name="options"/> (null for the defaults) is read for the
        /// sim_* keys and not kept. The sheet starts flat.
        /// </summary>
        public SimulatedLine(Calibration? calibration = null, FlatlineOptions? options = null)
        {
            if (calibration == null)
            {
                calibration = Calibration.Reference();
                ownsCalibration = true;
            }
            try
            {
                using (var scope = FlatlineOptions.Borrow(options))
                {
                    FlatlineNative.flt_sim_create(calibration.LiveHandle, scope.Handle, out handle);
                }
            }
            catch
            {
                if (ownsCalibration)
                    calibration.Dispose();
                throw;
            }
            Calibration = calibration;
            FlatlineNative.flt_sim_fibers(handle, out UIntPtr fibers);
            FlatlineNative.flt_sim_frame_size(handle, out uint width, out uint height);
            FlatlineNative.flt_sim_pixel_format(handle, out int format);
            Fibers = checked((int)fibers.ToUInt64());
            FrameWidth = (int)width;
            FrameHeight = (int)height;
            PixelFormat = (PixelFormat)format;
            handle.Track(NativeBytes());
        }

        /// <summary>The calibration the line was created from (the reference
        /// sensor's when none was given).</summary>
        public Calibration Calibration { get; }

        /// <summary>The number of fibers (the calibration's grid).</summary>
        public int Fibers { get; }
        /// <summary>The frame width, px.</summary>
        public int FrameWidth { get; }
        /// <summary>The frame height, px.</summary>
        public int FrameHeight { get; }
        /// <summary>The pixel format of <see cref="NextFrame()"/> (from sim_bit_depth).</summary>
        public PixelFormat PixelFormat { get; }

        /// <summary>Adds a defect: <paramref name="amplitudeMm"/> finite,
        /// <paramref name="periodMm"/> &gt;= 0 (0: constant along travel). At
        /// most 64 (then <see cref="BufferFullException"/>).</summary>
        public void AddDefect(DefectKind kind, double amplitudeMm, double periodMm = 0.0) =>
            FlatlineNative.flt_sim_add_defect(LiveHandle, (NativeDefect)kind, amplitudeMm, periodMm);

        /// <summary>Removes every defect and the height map: the sheet is flat again.</summary>
        public void ClearSheet() => FlatlineNative.flt_sim_clear_sheet(LiveHandle);

        /// <summary>
        /// Adds a height map to the sheet (replacing a previous one):
        /// <paramref name="heights"/> [rows, cols] mm (rows, cols &gt;= 2), row r
        /// at s = s0Mm + r * dsMm, column c at x = x0Mm + c * dxMm (ds, dx &gt; 0).
        /// Interpolated bilinearly, clamped to the edge values outside. Copied.
        /// </summary>
        public unsafe void SetHeightMap(double[,] heights, double s0Mm, double dsMm, double x0Mm, double dxMm)
        {
            var live = LiveHandle;
            if (heights == null)
                throw new ArgumentNullException(nameof(heights));
            if (heights.GetLength(0) < 2 || heights.GetLength(1) < 2)
                throw new ArgumentException(
                    $"heights is [{heights.GetLength(0)}, {heights.GetLength(1)}] but needs at least 2 rows " +
                    "and 2 columns to interpolate", nameof(heights));
            fixed (double* ph = heights)
            {
                FlatlineNative.flt_sim_set_height_map(live, (ulong)heights.GetLength(0), (ulong)heights.GetLength(1),
                                                      s0Mm, dsMm, x0Mm, dxMm, ph);
            }
        }

        /// <summary>The ground truth: the sheet's height at (x, s), mm.</summary>
        public unsafe double Surface(double x, double s)
        {
            var live = LiveHandle;
            double z;
            FlatlineNative.flt_sim_surface(live, 1, &x, &s, &z);
            return z;
        }

        /// <summary>The ground truth at the points (x[i], s[i]), mm.</summary>
        public unsafe double[] Surface(double[] x, double[] s)
        {
            var live = LiveHandle;
            if (x == null)
                throw new ArgumentNullException(nameof(x));
            Shapes.Check(s, x.Length, nameof(s));
            var z = new double[x.Length];
            fixed (double* px = x, ps = s, pz = z)
            {
                FlatlineNative.flt_sim_surface(live, (ulong)x.Length, px, ps, pz);
            }
            return z;
        }

        /// <summary>The next <paramref name="rows"/> profile rows (frames f ..
        /// f + rows - 1).</summary>
        public unsafe SimulatedRows NextRows(int rows)
        {
            var live = LiveHandle;
            Shapes.AtLeast(rows, 1, nameof(rows));
            var encoder = new double[rows];
            var s = new double[rows];
            var height = new double[rows, Fibers];
            var slope = new double[rows, Fibers];
            var valid = new bool[rows, Fibers];
            var truth = new double[rows, Fibers];
            fixed (double* pe = encoder, ps = s, ph = height, pg = slope, pt = truth)
            fixed (bool* pv = valid)
            {
                FlatlineNative.flt_sim_next_rows(live, (ulong)rows, (ulong)Fibers, pe, ps, ph, pg, (byte*)pv, pt);
            }
            return new SimulatedRows(encoder, s, height, slope, valid, truth);
        }

        /// <summary>Renders the next frame into new arrays, with its encoder
        /// position, the truth per fiber and the exact line centres.</summary>
        public SimulatedFrame NextFrame()
        {
            var truth = new double[Fibers];
            var peakRows = new double[Calibration.Lasers, FrameWidth];
            if (PixelFormat == PixelFormat.Mono8)
            {
                var pixels = new byte[FrameHeight, FrameWidth];
                double encoder = NextFrame(pixels, truth, peakRows);
                return new SimulatedFrame(PixelFormat, pixels, encoder, truth, peakRows);
            }
            else
            {
                var pixels = new ushort[FrameHeight, FrameWidth];
                double encoder = NextFrame(pixels, truth, peakRows);
                return new SimulatedFrame(PixelFormat, pixels, encoder, truth, peakRows);
            }
        }

        /// <summary>Renders the next Mono8 frame into <paramref name="pixels"/>
        /// [FrameHeight, FrameWidth] (a SCADA loop reuses its buffers) and
        /// returns its encoder position, mm. <paramref name="truth"/> [fibers]
        /// and <paramref name="peakRows"/> [2, FrameWidth] are filled when
        /// given. <see cref="ArgumentException"/> for a wrong size or a 16-bit
        /// <see cref="PixelFormat"/>, before the native call.</summary>
        public unsafe double NextFrame(byte[,] pixels, double[]? truth = null, double[,]? peakRows = null)
        {
            var live = LiveHandle;
            if (PixelFormat != PixelFormat.Mono8)
                throw new ArgumentException($"the line renders {PixelFormat} frames: pass a ushort[,]", nameof(pixels));
            CheckFrame(pixels, truth, peakRows);
            fixed (byte* pp = pixels)
                return Render(live, pp, sizeof(byte), truth, peakRows);
        }

        /// <summary>The same for Mono10, Mono12 and Mono16 frames.</summary>
        public unsafe double NextFrame(ushort[,] pixels, double[]? truth = null, double[,]? peakRows = null)
        {
            var live = LiveHandle;
            if (PixelFormat == PixelFormat.Mono8)
                throw new ArgumentException("the line renders Mono8 frames: pass a byte[,]", nameof(pixels));
            CheckFrame(pixels, truth, peakRows);
            fixed (ushort* pp = pixels)
                return Render(live, pp, sizeof(ushort), truth, peakRows);
        }

        /// <summary>Ground truth of the strip's edges at the encoder
        /// positions (mm, finite) under laser 0 or 1, or 2 (the default) for
        /// a profile row (the mean of both lasers' edges, present only where
        /// both see the strip): sensor x of each edge, NaN where the laser
        /// sees no strip (Present false).</summary>
        public unsafe SimulatedEdges StripEdges(double[] encoderMm, int laser = 2)
        {
            var live = LiveHandle;
            if (encoderMm == null)
                throw new ArgumentNullException(nameof(encoderMm));
            if (laser < 0 || laser > 2)
                throw new ArgumentOutOfRangeException(nameof(laser), laser, "laser must be 0, 1 or 2 (the profile row)");
            int n = encoderMm.Length;
            var left = new double[n];
            var right = new double[n];
            var present = new bool[n];
            if (n > 0)
                fixed (double* pe = encoderMm, pl = left, pr = right)
                fixed (bool* pp = present)
                {
                    FlatlineNative.flt_sim_strip_edges(live, (uint)laser, (ulong)n, pe, pl, pr, (byte*)pp);
                }
            return new SimulatedEdges(left, right, present);
        }

        /// <summary>Ground truth of a frame's fiber flags at
        /// <paramref name="encoderMm"/>: what a perfect extractor reports
        /// (<see cref="Extractor.FiberFlags"/>): None on the strip for both
        /// lasers, <see cref="ReconFlags.OffStrip"/> otherwise.</summary>
        public unsafe ReconFlags[] FiberFlags(double encoderMm)
        {
            var live = LiveHandle;
            var flags = new ReconFlags[Fibers];
            fixed (ReconFlags* pf = flags)
            {
                FlatlineNative.flt_sim_fiber_flags(live, encoderMm, (ulong)Fibers, (byte*)pf);
            }
            return flags;
        }

        /// <summary>Back to frame 0: the following output repeats the first exactly.</summary>
        public void Rewind() => FlatlineNative.flt_sim_rewind(LiveHandle);

        /// <summary>Frees the native simulator now (and the reference
        /// calibration it made for itself, if any; a calibration the caller
        /// gave stays the caller's). Further calls throw
        /// <see cref="ObjectDisposedException"/>; a second Dispose does nothing.</summary>
        public void Dispose()
        {
            handle.Dispose();
            if (ownsCalibration)
                Calibration.Dispose();
            GC.SuppressFinalize(this);
        }

        internal SimHandle LiveHandle
        {
            get
            {
                if (handle.IsDisposed)
                    throw new ObjectDisposedException(nameof(SimulatedLine));
                return handle;
            }
        }

        private void CheckFrame<T>(T[,] pixels, double[]? truth, double[,]? peakRows)
        {
            if (pixels == null)
                throw new ArgumentNullException(nameof(pixels));
            if (pixels.GetLength(0) != FrameHeight || pixels.GetLength(1) != FrameWidth)
                throw new ArgumentException(
                    $"pixels is [{pixels.GetLength(0)}, {pixels.GetLength(1)}] but must be " +
                    $"[{FrameHeight}, {FrameWidth}] (rows, columns of the frame)", nameof(pixels));
            if (truth != null)
                Shapes.Check(truth, Fibers, nameof(truth));
            if (peakRows != null && (peakRows.GetLength(0) != Calibration.Lasers || peakRows.GetLength(1) != FrameWidth))
                throw new ArgumentException(
                    $"peakRows is [{peakRows.GetLength(0)}, {peakRows.GetLength(1)}] but must be " +
                    $"[2, {FrameWidth}] (laser, column)", nameof(peakRows));
        }

        private unsafe double Render(SimHandle live, void* pixels, int bytesPerPixel, double[]? truth, double[,]? peakRows)
        {
            ulong stride = (ulong)(FrameWidth * bytesPerPixel);
            double encoder;
            fixed (double* pt = truth, pk = peakRows)
            {
                FlatlineNative.flt_sim_next_frame(live, pixels, stride * (ulong)FrameHeight, stride, &encoder,
                                                  truth == null ? 0UL : (ulong)Fibers, pt, pk,
                                                  peakRows == null ? 0UL : (ulong)peakRows.Length);
            }
            return encoder;
        }

        /// <summary>The native memory held (sim.h: the frame scratch of 4
        /// bytes per pixel, plus per column the lines' polylines and centre
        /// rows), reported to the GC as memory pressure.</summary>
        private long NativeBytes() => 4L * FrameWidth * FrameHeight + 64L * FrameWidth + 16L * Fibers;
    }
}
