// SPDX-License-Identifier: Apache-2.0
using System;

namespace Flatline
{
    /// <summary>Pixel formats of a frame (flt_pixel_format); the value is
    /// the number of significant bits. Mono8 frames are <c>byte[rows,
    /// columns]</c>; Mono10, Mono12 and Mono16 frames are <c>ushort[rows,
    /// columns]</c> with the data in the low bits (GenICam unpacked formats).</summary>
    public enum PixelFormat
    {
        Mono8 = NativePixelFormat.FLT_PIXEL_MONO8,
        Mono10 = NativePixelFormat.FLT_PIXEL_MONO10,
        Mono12 = NativePixelFormat.FLT_PIXEL_MONO12,
        Mono16 = NativePixelFormat.FLT_PIXEL_MONO16,
    }


    /// <summary>What <see cref="Extractor.Strip"/> could not see
    /// (FLT_STRIP_*); bits combine.</summary>
    [Flags]
    public enum StripFlags : uint
    {
        None = 0,
        /// <summary>No strip under the laser (a head or tail between coils,
        /// or no line): every value is NaN; both open bits are set too.</summary>
        NoStrip = FlatlineNative.FLT_STRIP_NONE,
        /// <summary>The strip reaches the frame's border at low sensor x:
        /// <see cref="StripEdges.LeftMm"/> is NaN.</summary>
        LeftOpen = FlatlineNative.FLT_STRIP_LEFT_OPEN,
        /// <summary>The same at high sensor x: <see cref="StripEdges.RightMm"/> is NaN.</summary>
        RightOpen = FlatlineNative.FLT_STRIP_RIGHT_OPEN,
        /// <summary>A glint lay on the edge at low sensor x, which pushes a
        /// measured edge outward. One laser: its own edge had it (the value is
        /// the other laser's where that one was clean); the row (laser 2): both
        /// had it, and <see cref="StripEdges.LeftMm"/> may lie up to about
        /// 1.5 mm outward.</summary>
        LeftGlint = FlatlineNative.FLT_STRIP_LEFT_GLINT,
        /// <summary>The same at high sensor x.</summary>
        RightGlint = FlatlineNative.FLT_STRIP_RIGHT_GLINT,
    }

    /// <summary>Where the last frame shows the strip, sensor x in mm; a value
    /// is NaN exactly where <see cref="Flags"/> says why.</summary>
    public readonly struct StripEdges
    {
        internal StripEdges(double left, double right, double width, double centre, StripFlags flags)
        {
            LeftMm = left;
            RightMm = right;
            WidthMm = width;
            CentreMm = centre;
            Flags = flags;
        }

        /// <summary>The edge at low sensor x, mm.</summary>
        public double LeftMm { get; }
        /// <summary>The edge at high sensor x, mm.</summary>
        public double RightMm { get; }
        /// <summary>Right minus left, mm; NaN unless both edges are seen.</summary>
        public double WidthMm { get; }
        /// <summary>The centre line's sensor x, mm; NaN unless both edges are seen.</summary>
        public double CentreMm { get; }
        /// <summary>Which values are NaN and why.</summary>
        public StripFlags Flags { get; }
        public override string ToString() => $"strip {LeftMm:F2} .. {RightMm:F2} mm ({Flags})";
    }

    /// <summary>The last frame's saturated peaks on the strip, for an
    /// exposure controller.</summary>
    public readonly struct SaturationCount
    {
        internal SaturationCount(ulong peaks, ulong saturated, double fraction)
        {
            Peaks = peaks;
            Saturated = saturated;
            Fraction = fraction;
        }

        /// <summary>The strip's columns with a valid peak.</summary>
        public ulong Peaks { get; }
        /// <summary>Of those, the saturated ones (measured as a plateau).</summary>
        public ulong Saturated { get; }
        /// <summary>Saturated / peaks; 0 without a peak.</summary>
        public double Fraction { get; }
    }

    /// <summary>A laser's band of frame rows: the rows the extractor searches
    /// for that laser's line, px.</summary>
    public readonly struct RowBand : IEquatable<RowBand>
    {
        public RowBand(int firstRow, int rows)
        {
            FirstRow = firstRow;
            Rows = rows;
        }

        public int FirstRow { get; }
        public int Rows { get; }
        public bool Equals(RowBand other) => FirstRow == other.FirstRow && Rows == other.Rows;
        public override bool Equals(object? obj) => obj is RowBand other && Equals(other);
        public override int GetHashCode() => FirstRow * 65537 + Rows;
        public override string ToString() => $"rows {FirstRow} .. {FirstRow + Rows - 1}";
    }

    /// <summary>
    /// One profile row from <see cref="Extractor.Process(byte[,], double)"/>:
    /// per fiber the height (mm) and slope (mm/mm) the two lasers measured,
    /// NaN and <see cref="Valid"/> false where either laser gave no valid
    /// peak. <see cref="S"/> is the row's material position, mm. Exactly what
    /// <see cref="Reconstructor.Push(double, double[], double[], bool[])"/> takes.
    /// </summary>
    public sealed class ProfileRow
    {
        internal ProfileRow(double encoderMm, double s, double[] height, double[] slope, bool[] valid)
        {
            EncoderMm = encoderMm;
            S = s;
            Height = height;
            Slope = slope;
            Valid = valid;
        }

        /// <summary>The frame's encoder position, mm.</summary>
        public double EncoderMm { get; }
        /// <summary>The row's material position: the encoder position minus
        /// the mean of the two laser offsets, mm.</summary>
        public double S { get; }
        /// <summary>[fibers] mean of the two lasers' heights, mm; NaN where invalid.</summary>
        public double[] Height { get; }
        /// <summary>[fibers] (z ahead - z behind) / laser spacing, mm/mm; NaN where invalid.</summary>
        public double[] Slope { get; }
        /// <summary>[fibers] true where both lasers gave a valid height.</summary>
        public bool[] Valid { get; }
        public int Fibers => Height.Length;
    }

    /// <summary>
    /// The frame-to-profile extractor (flt_extractor): per camera column and
    /// laser the strongest valid peak, refined to sub-pixel, mapped through
    /// the calibration to (x, z) mm and resampled on the fiber grid; then per
    /// fiber the height and slope of the two lasers. See
    /// include/flatline/extractor.h for the method, the bands of rows and the
    /// pixel formats.
    /// </summary>
    /// <remarks>
    /// Holds its <see cref="Calibration"/> (the GC cannot collect it while the
    /// extractor lives; the native extractor copied it at creation, so even a
    /// disposed calibration does not stop it). Not thread-safe: one thread at
    /// a time; separate extractors, even of one calibration, are independent.
    /// </remarks>
    public sealed class Extractor : IDisposable
    {
        private readonly ExtractorHandle handle;

        static Extractor() => NativeLoader.EnsureLoaded();

        /// <summary>An extractor for frames of <paramref name="calibration"/>
        /// (finished, else <see cref="FlatlineStateException"/>).
        /// <paramref name="options"/> (null for the defaults) is read for the
        /// extract_* keys and not kept; <see cref="InvalidArgumentException"/>
        /// for a band outside the frame or an unusable Savitzky-Golay window.</summary>
        public Extractor(Calibration calibration, FlatlineOptions? options = null)
        {
            if (calibration == null)
                throw new ArgumentNullException(nameof(calibration));
            using (var scope = FlatlineOptions.Borrow(options))
            {
                FlatlineNative.flt_extractor_create(calibration.LiveHandle, scope.Handle, out handle);
            }
            Calibration = calibration;
            FlatlineNative.flt_extractor_fibers(handle, out UIntPtr fibers);
            Fibers = checked((int)fibers.ToUInt64());
            FrameWidth = calibration.FrameWidth;
            FrameHeight = calibration.FrameHeight;
            handle.Track(NativeBytes());
        }

        /// <summary>The calibration the extractor was created from.</summary>
        public Calibration Calibration { get; }
        /// <summary>The fibers of a profile row (the calibration's fiber count).</summary>
        public int Fibers { get; }
        /// <summary>The frame width, px (the calibration's).</summary>
        public int FrameWidth { get; }
        /// <summary>The frame height, px (the calibration's).</summary>
        public int FrameHeight { get; }

        /// <summary>Laser <paramref name="laser"/>'s band of rows.
        /// <see cref="FlatlineStateException"/> while an automatic band
        /// (extract_laserL_rows = 0) waits for its first frame.</summary>
        public RowBand Band(int laser)
        {
            var live = LiveHandle;
            FlatlineNative.flt_extractor_band(live, Shapes.Laser(laser), out uint first, out uint rows);
            return new RowBand((int)first, (int)rows);
        }

        /// <summary>Turns one Mono8 frame [FrameHeight, FrameWidth] taken at
        /// encoder position <paramref name="encoderMm"/> (mm, finite) into a
        /// profile row. A wrong frame size throws <see cref="ArgumentException"/>
        /// before the native call.</summary>
        public ProfileRow Process(byte[,] frame, double encoderMm)
        {
            NewRow(out double[] height, out double[] slope, out bool[] valid);
            double s = Process(frame, encoderMm, height, slope, valid);
            return new ProfileRow(encoderMm, s, height, slope, valid);
        }

        /// <summary>The same for a 16-bit frame of <paramref name="format"/>
        /// (Mono10, Mono12 or Mono16: the data in the low bits, full scale
        /// 2^bits - 1).</summary>
        public ProfileRow Process(ushort[,] frame, PixelFormat format, double encoderMm)
        {
            NewRow(out double[] height, out double[] slope, out bool[] valid);
            double s = Process(frame, format, encoderMm, height, slope, valid);
            return new ProfileRow(encoderMm, s, height, slope, valid);
        }

        /// <summary>A simulated frame, with its own pixel format and encoder position.</summary>
        public ProfileRow Process(SimulatedFrame frame)
        {
            if (frame == null)
                throw new ArgumentNullException(nameof(frame));
            return frame.Pixels is byte[,] pixels8
                ? Process(pixels8, frame.EncoderMm)
                : Process((ushort[,])frame.Pixels, frame.Format, frame.EncoderMm);
        }

        /// <summary>Processes a Mono8 frame into the caller's arrays
        /// <paramref name="height"/>, <paramref name="slope"/> and (optional)
        /// <paramref name="valid"/>, each [fibers] (a SCADA loop reuses them;
        /// nothing is allocated), and returns the row's material position, mm.</summary>
        public unsafe double Process(byte[,] frame, double encoderMm, double[] height, double[] slope, bool[]? valid = null)
        {
            var live = LiveHandle;
            CheckFrame(frame, height, slope, valid);
            fixed (byte* pf = frame)
                return Run(live, pf, PixelFormat.Mono8, sizeof(byte), encoderMm, height, slope, valid);
        }

        /// <summary>The same for a 16-bit frame of <paramref name="format"/>.</summary>
        public unsafe double Process(ushort[,] frame, PixelFormat format, double encoderMm, double[] height,
                                     double[] slope, bool[]? valid = null)
        {
            var live = LiveHandle;
            if (format == PixelFormat.Mono8)
                throw new ArgumentException("a ushort[,] frame is Mono10, Mono12 or Mono16; pass Mono8 frames as byte[,]",
                                            nameof(format));
            CheckFrame(frame, height, slope, valid);
            fixed (ushort* pf = frame)
                return Run(live, pf, format, sizeof(ushort), encoderMm, height, slope, valid);
        }

        /// <summary>Diagnostics of the last processed frame: [2, FrameWidth],
        /// per laser and column the sub-pixel row of its peak (px, raw image
        /// rows), NaN where the column has no valid peak.
        /// <see cref="FlatlineStateException"/> before the first successful Process.</summary>
        public unsafe double[,] Peaks()
        {
            var live = LiveHandle;
            var rows = new double[Calibration.Lasers, FrameWidth];
            fixed (double* pr = rows)
            {
                FlatlineNative.flt_extractor_peaks(live, (ulong)FrameWidth, pr);
            }
            return rows;
        }

        /// <summary>Diagnostics of the last processed frame: [2, fibers], each
        /// laser's z on the fiber grid (mm), NaN where invalid; laser L read
        /// the material at s = encoder - offset of L.</summary>
        public unsafe double[,] LaserProfiles()
        {
            var live = LiveHandle;
            var z = new double[Calibration.Lasers, Fibers];
            fixed (double* pz = z)
            {
                FlatlineNative.flt_extractor_laser_profiles(live, (ulong)Fibers, pz);
            }
            return z;
        }

        /// <summary>The last processed frame's flags per fiber: 0 valid,
        /// <see cref="ReconFlags.OffStrip"/> off the strip,
        /// <see cref="ReconFlags.InvalidInput"/> on the strip without a valid
        /// height from both lasers. Exactly what
        /// <see cref="Reconstructor.PushFlagged(double[], double[,], double[,], ReconFlags[,])"/> takes.
        /// <see cref="FlatlineStateException"/> before the first frame.</summary>
        public unsafe ReconFlags[] FiberFlags()
        {
            var live = LiveHandle;
            var flags = new ReconFlags[Fibers];
            fixed (ReconFlags* pf = flags)
            {
                FlatlineNative.flt_extractor_fiber_flags(live, (ulong)Fibers, (byte*)pf);
            }
            return flags;
        }

        /// <summary>Where the last processed frame shows the strip under laser
        /// 0 or 1, or 2 (the default) for the profile row (the mean of both
        /// lasers' edges). <see cref="FlatlineStateException"/> before the
        /// first frame.</summary>
        public unsafe StripEdges Strip(int laser = 2)
        {
            var live = LiveHandle;
            double left, right, width, centre;
            uint flags;
            FlatlineNative.flt_extractor_strip(live, LaserOrRow(laser), &left, &right, &width, &centre,
                                               &flags);
            return new StripEdges(left, right, width, centre, (StripFlags)flags);
        }

        /// <summary>The last processed frame's saturated peaks on the strip,
        /// under laser 0 or 1, or 2 (the default) for both.</summary>
        public unsafe SaturationCount Saturation(int laser = 2)
        {
            var live = LiveHandle;
            ulong peaks, saturated;
            double fraction;
            FlatlineNative.flt_extractor_saturation(live, LaserOrRow(laser), &peaks, &saturated,
                                                    &fraction);
            return new SaturationCount(peaks, saturated, fraction);
        }

        private static uint LaserOrRow(int laser)
        {
            if (laser < 0 || laser > 2)
                throw new ArgumentOutOfRangeException(nameof(laser), laser,
                                                      "laser must be 0, 1 or 2 (the profile row)");
            return (uint)laser;
        }

        /// <summary>Frees the native extractor now. Further calls throw
        /// <see cref="ObjectDisposedException"/>; a second Dispose does nothing.
        /// The calibration stays the caller's.</summary>
        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }

        private ExtractorHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(Extractor));
                return handle;
            }
        }

        private void NewRow(out double[] height, out double[] slope, out bool[] valid)
        {
            height = new double[Fibers];
            slope = new double[Fibers];
            valid = new bool[Fibers];
        }

        private void CheckFrame<T>(T[,] frame, double[] height, double[] slope, bool[]? valid)
        {
            if (frame == null)
                throw new ArgumentNullException(nameof(frame));
            if (frame.GetLength(0) != FrameHeight || frame.GetLength(1) != FrameWidth)
                throw new ArgumentException(
                    $"frame is [{frame.GetLength(0)}, {frame.GetLength(1)}] but must be " +
                    $"[{FrameHeight}, {FrameWidth}] (rows, columns: the calibration's frame size)", nameof(frame));
            Shapes.Check(height, Fibers, nameof(height));
            Shapes.Check(slope, Fibers, nameof(slope));
            if (valid != null)
                Shapes.Check(valid, Fibers, nameof(valid));
        }

        private unsafe double Run(ExtractorHandle live, void* frame, PixelFormat format, int bytesPerPixel,
                                  double encoderMm, double[] height, double[] slope, bool[]? valid)
        {
            double s;
            fixed (double* ph = height, pg = slope)
            fixed (bool* pv = valid)
            {
                FlatlineNative.flt_extractor_process(live, frame, (int)format, (uint)FrameWidth, (uint)FrameHeight,
                                                     (ulong)(FrameWidth * bytesPerPixel), encoderMm, (ulong)Fibers,
                                                     &s, ph, pg, (byte*)pv);
            }
            return s;
        }

        /// <summary>The native memory held (extractor.h: everything is
        /// allocated at create): per column the two lasers' polynomial maps
        /// (192 bytes), their fitting scratch (384) and peak buffers (~64),
        /// per row a sum, per fiber the fit sums; reported to the GC as
        /// memory pressure.</summary>
        private long NativeBytes() => 640L * FrameWidth + 8L * FrameHeight + 96L * Fibers;
    }
}
