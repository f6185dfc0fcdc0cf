// SPDX-License-Identifier: Apache-2.0
using System;

namespace Flatline
{
    /// <summary>The length I-Units are measured against (the option
    /// "flat_reference", flt_flat_reference in flatline/flatness.h).</summary>
    public enum FlatReference
    {
        /// <summary>The shortest valid fiber (the default).</summary>
        Shortest = NativeFlatReference.FLT_FLAT_REFERENCE_SHORTEST,
        /// <summary>The mean of the valid fibers.</summary>
        Mean = NativeFlatReference.FLT_FLAT_REFERENCE_MEAN,
    }

    /// <summary>Where zones are laid (the option "flat_zones_on",
    /// flt_zones_on in flatline/flatness.h).</summary>
    public enum ZonesOn
    {
        /// <summary>On the strip, from its edges, where they are known (the default).</summary>
        Strip = NativeZonesOn.FLT_ZONES_ON_STRIP,
        /// <summary>On the sensor's fiber grid, whatever the strip does.</summary>
        Grid = NativeZonesOn.FLT_ZONES_ON_GRID,
    }

    /// <summary>The sensor side of the leveler's drive side (the option
    /// "flat_drive_side", flt_side in flatline/flatness.h).</summary>
    public enum DriveSide
    {
        /// <summary>At the sensor's low x (the default).</summary>
        LowX = NativeSide.FLT_SIDE_LOW_X,
        /// <summary>At the sensor's high x.</summary>
        HighX = NativeSide.FLT_SIDE_HIGH_X,
    }

    /// <summary>The shape class of a window (flt_shape), from its zone
    /// I-Unit profile; see include/flatline/flatness.h for the rule.</summary>
    public enum ShapeClass
    {
        Flat = NativeShape.FLT_SHAPE_FLAT,
        CentreBuckle = NativeShape.FLT_SHAPE_CENTRE_BUCKLE,
        /// <summary>Long material at x &lt; centre.</summary>
        WavyEdgeLeft = NativeShape.FLT_SHAPE_WAVY_EDGE_LEFT,
        WavyEdgeRight = NativeShape.FLT_SHAPE_WAVY_EDGE_RIGHT,
        /// <summary><see cref="WavyEdgeLeft"/> by the operator's name
        /// (FlatDriveSide says which sensor side it is).</summary>
        WavyEdgeDriveSide = NativeShape.FLT_SHAPE_WAVY_EDGE_DRIVE_SIDE,
        /// <summary><see cref="WavyEdgeRight"/> by the operator's name.</summary>
        WavyEdgeOperatorSide = NativeShape.FLT_SHAPE_WAVY_EDGE_OPERATOR_SIDE,
        WavyEdgeBoth = NativeShape.FLT_SHAPE_WAVY_EDGE_BOTH,
        QuarterBuckle = NativeShape.FLT_SHAPE_QUARTER_BUCKLE,
        /// <summary>Two or more component groups; see <see cref="ShapeComponents"/>.</summary>
        Mix = NativeShape.FLT_SHAPE_MIX,
        /// <summary>Too short a window, no valid fiber, or fewer than 5 valid zones.</summary>
        Undetermined = NativeShape.FLT_SHAPE_UNDETERMINED,
        /// <summary>Not judged: the gauge's sheet is incomplete (<see cref="Sheet.Incomplete"/>).</summary>
        NotJudged = NativeShape.FLT_SHAPE_NOT_JUDGED,
    }

    /// <summary>Components of a shape (FLT_SHAPE_HAS_*). Bow and Crossbow
    /// are set from FlatBowLimit / FlatCrossbowLimit and do not change the class.</summary>
    [Flags]
    public enum ShapeComponents : uint
    {
        None = 0,
        Centre = FlatlineNative.FLT_SHAPE_HAS_CENTRE,
        EdgeLeft = FlatlineNative.FLT_SHAPE_HAS_EDGE_LEFT,
        EdgeRight = FlatlineNative.FLT_SHAPE_HAS_EDGE_RIGHT,
        Quarter = FlatlineNative.FLT_SHAPE_HAS_QUARTER,
        Bow = FlatlineNative.FLT_SHAPE_HAS_BOW,
        Crossbow = FlatlineNative.FLT_SHAPE_HAS_CROSSBOW,
    }

    /// <summary>Per-fiber result flags (FLT_FIBER_*). A NaN result always
    /// carries the flag that explains it.</summary>
    [Flags]
    public enum FiberFlags : byte
    {
        None = 0,
        /// <summary>Less than FlatMinCoverage usable: arc length, I-Units and wave NaN.</summary>
        NoData = FlatlineNative.FLT_FIBER_NO_DATA,
        /// <summary>No complete wave above FlatWaveHysteresis: wave height, period, steepness NaN.</summary>
        NoWave = FlatlineNative.FLT_FIBER_NO_WAVE,
        /// <summary>Some rows unusable; the arc length is scaled from the covered part.</summary>
        Partial = FlatlineNative.FLT_FIBER_PARTIAL,
        /// <summary>The result slot lies beyond the strip's edges (zones on
        /// the strip); NoData is set too.</summary>
        OffStrip = FlatlineNative.FLT_FIBER_OFF_STRIP,
    }

    /// <summary>Per-zone result flags (FLT_ZONE_*).</summary>
    [Flags]
    public enum ZoneFlags : byte
    {
        None = 0,
        /// <summary>No valid fiber in the zone: its I-Units are NaN.</summary>
        NoData = FlatlineNative.FLT_ZONE_NO_DATA,
        /// <summary>The zone lies beyond the strip's zones (a strip narrower
        /// than the grid); NoData is set too.</summary>
        OffStrip = FlatlineNative.FLT_ZONE_OFF_STRIP,
    }

    /// <summary>Per-window flags (FLT_WINDOW_*).</summary>
    [Flags]
    public enum WindowFlags : uint
    {
        None = 0,
        /// <summary>Shorter than FlatMinLength: no wave, shape Undetermined.</summary>
        Short = FlatlineNative.FLT_WINDOW_SHORT,
        /// <summary>No fiber is valid: every value NaN and flagged.</summary>
        NoValidFiber = FlatlineNative.FLT_WINDOW_NO_VALID_FIBER,
        /// <summary>BowMm is NaN.</summary>
        NoBow = FlatlineNative.FLT_WINDOW_NO_BOW,
        /// <summary>CrossbowMm is NaN.</summary>
        NoCrossbow = FlatlineNative.FLT_WINDOW_NO_CROSSBOW,
        /// <summary>The strip's edges were known: fibers and zones lie on
        /// the strip (see <see cref="StripWindow"/>).</summary>
        OnStrip = FlatlineNative.FLT_WINDOW_ON_STRIP,
    }

    /// <summary>Where one window's results lie on the strip. With
    /// <see cref="WindowFlags.OnStrip"/> result fiber k is the strip
    /// coordinate <see cref="FiberStripX"/>[k] (mm from the strip's centre
    /// line towards the operator side), not sensor fiber k, and zones are
    /// laid on the strip; without it, on the fiber grid.</summary>
    public sealed class StripWindow
    {
        internal StripWindow(bool onStrip, double[] widthMm, double[] centreMm, double[] fiberStripX,
                             double[] fiberSensorX, double[] zoneStripCentre, double[] zoneSensorCentre,
                             double[] zoneWidth, int[] zoneFiberCount)
        {
            OnStrip = onStrip;
            WidthMm = widthMm;
            CentreMm = centreMm;
            FiberStripX = fiberStripX;
            FiberSensorX = fiberSensorX;
            ZoneStripCentre = zoneStripCentre;
            ZoneSensorCentre = zoneSensorCentre;
            ZoneWidth = zoneWidth;
            ZoneFiberCount = zoneFiberCount;
        }

        /// <summary>The window was measured on the strip.</summary>
        public bool OnStrip { get; }
        /// <summary>[3] the strip's width over the window: mean, min, max, mm.</summary>
        public double[] WidthMm { get; }
        /// <summary>[3] its centre line's sensor x: mean, min, max, mm.</summary>
        public double[] CentreMm { get; }
        /// <summary>[fibers] each result fiber's strip coordinate, mm.</summary>
        public double[] FiberStripX { get; }
        /// <summary>[fibers] its sensor x at the window's mean position, mm.</summary>
        public double[] FiberSensorX { get; }
        /// <summary>[zones] zone centres in strip coordinates, mm; NaN off the strip.</summary>
        public double[] ZoneStripCentre { get; }
        /// <summary>[zones] zone centres in sensor x, mm; NaN off the strip.</summary>
        public double[] ZoneSensorCentre { get; }
        /// <summary>[zones] zone widths, mm (0 off the strip).</summary>
        public double[] ZoneWidth { get; }
        /// <summary>[zones] result fibers in each zone.</summary>
        public int[] ZoneFiberCount { get; }
    }

    /// <summary>What <see cref="Flatness.Push"/> did: the rows it took (all
    /// of them unless a window completed first) and whether a window was
    /// evaluated (its results are then in <see cref="Flatness.Result"/>).</summary>
    public readonly struct FlatnessPush
    {
        internal FlatnessPush(int consumed, bool evaluated)
        {
            Consumed = consumed;
            Evaluated = evaluated;
        }

        public int Consumed { get; }
        public bool Evaluated { get; }
        public override string ToString() => $"{Consumed} rows taken{(Evaluated ? ", window evaluated" : "")}";
    }

    /// <summary>The evaluated window: the s of its first and last row (mm),
    /// its rows, flags and sequence number (1 for the first window).</summary>
    public sealed class FlatnessWindow
    {
        internal FlatnessWindow(double sFirstMm, double sLastMm, int rows, WindowFlags flags, long index)
        {
            SFirstMm = sFirstMm;
            SLastMm = sLastMm;
            Rows = rows;
            Flags = flags;
            Index = index;
        }

        public double SFirstMm { get; }
        public double SLastMm { get; }
        public double LengthMm => SLastMm - SFirstMm;
        public int Rows { get; }
        public WindowFlags Flags { get; }
        public long Index { get; }
        public override string ToString() =>
            FormattableString.Invariant($"window {Index}: s {SFirstMm:F1} .. {SLastMm:F1} mm, {Rows} rows");
    }

    /// <summary>Per-fiber results of a window, [fibers] each.</summary>
    public sealed class FiberResults
    {
        internal FiberResults(int fibers)
        {
            ArcLength = new double[fibers];
            IUnits = new double[fibers];
            WaveHeight = new double[fibers];
            WavePeriod = new double[fibers];
            SteepnessPercent = new double[fibers];
            Flags = new FiberFlags[fibers];
        }

        /// <summary>Arc length of z(s) over the window, mm.</summary>
        public double[] ArcLength { get; }
        /// <summary>(l - l_ref) / l_ref * 1e5.</summary>
        public double[] IUnits { get; }
        /// <summary>Peak-to-peak height of the largest wave, mm.</summary>
        public double[] WaveHeight { get; }
        /// <summary>Period of the largest wave, mm.</summary>
        public double[] WavePeriod { get; }
        /// <summary>100 WaveHeight / WavePeriod, %.</summary>
        public double[] SteepnessPercent { get; }
        public FiberFlags[] Flags { get; }
        public int Count => IUnits.Length;
    }

    /// <summary>The zone profile of a window with the zone layout, [zones] each.</summary>
    public sealed class ZoneResults
    {
        internal ZoneResults(double[] iUnits, ZoneFlags[] flags, double[] leftX, double[] centreX, int[] fiberCount)
        {
            IUnits = iUnits;
            Flags = flags;
            LeftX = leftX;
            CentreX = centreX;
            FiberCount = fiberCount;
        }

        /// <summary>Mean I-Units of the zone's valid fibers.</summary>
        public double[] IUnits { get; }
        public ZoneFlags[] Flags { get; }
        /// <summary>Left edge of each zone, mm (the zone is FlatZoneWidth wide).</summary>
        public double[] LeftX { get; }
        /// <summary>Middle of each zone, mm.</summary>
        public double[] CentreX { get; }
        /// <summary>Fibers in each zone.</summary>
        public int[] FiberCount { get; }
        public int Count => IUnits.Length;
    }

    /// <summary>The shape of a window: class, confidence in [0, 1],
    /// components, and the bow and crossbow sagittas (mm; &gt; 0 when the
    /// ends / edges lie higher than the middle; NaN only with
    /// <see cref="WindowFlags.NoBow"/> / <see cref="WindowFlags.NoCrossbow"/>).</summary>
    public sealed class ShapeResult
    {
        internal ShapeResult(ShapeClass shapeClass, double confidence, ShapeComponents components, double bowMm,
                             double crossbowMm)
        {
            Class = shapeClass;
            Confidence = confidence;
            Components = components;
            BowMm = bowMm;
            CrossbowMm = crossbowMm;
        }

        public ShapeClass Class { get; }
        /// <summary>The C library's name of the class, e.g. "centre buckle".</summary>
        public string Name => Flatness.ShapeName(Class);
        public double Confidence { get; }
        public ShapeComponents Components { get; }
        public double BowMm { get; }
        public double CrossbowMm { get; }
        public override string ToString() => FormattableString.Invariant($"{Name} ({Confidence:P0})");
    }

    /// <summary>Everything about the last evaluated window.</summary>
    public sealed class FlatnessResult
    {
        internal FlatnessResult(FlatnessWindow window, FiberResults fibers, ZoneResults zones, ShapeResult shape,
                                StripWindow strip)
        {
            Window = window;
            Fibers = fibers;
            Zones = zones;
            Shape = shape;
            Strip = strip;
        }

        public FlatnessWindow Window { get; }
        public FiberResults Fibers { get; }
        public ZoneResults Zones { get; }
        public ShapeResult Shape { get; }
        /// <summary>Where the results lie on the strip.</summary>
        public StripWindow Strip { get; }
    }

    /// <summary>
    /// Flatness metrics (flt_flatness) of reconstructed rows: per fiber the
    /// arc length, I-Units and the largest wave; per zone the I-Unit profile
    /// a leveler operator reads; the shape class, bow and crossbow. Whole
    /// sheets with <see cref="Evaluate"/>, or a stream of rows with
    /// <see cref="Push"/> / <see cref="Finish"/> (a window every
    /// FlatUpdateInterval mm over the last FlatWindowLength mm). See
    /// include/flatline/flatness.h for the definitions, the NaN policy and
    /// the window grid.
    /// </summary>
    /// <remarks>
    /// Arrays are rows along travel × fibers across the width, as
    /// <see cref="Reconstructor"/> gives them: s [rows] mm, z [rows, fibers]
    /// mm, flags [rows, fibers] <see cref="ReconFlags"/> bits (or null).
    /// Created from a <see cref="Calibration"/>, it holds it (the GC cannot
    /// collect it while the metrics live; the native side only read its
    /// fiber grid at creation). Not thread-safe: one thread at a time;
    /// separate objects are independent.
    /// </remarks>
    public sealed class Flatness : IDisposable
    {
        private readonly FlatnessHandle handle;
        private readonly double[] zoneLeftX, zoneCentreX;
        private readonly int[] zoneFiberCount;

        static Flatness() => NativeLoader.EnsureLoaded();

        /// <summary>Metrics for fibers at <paramref name="fiberX"/> (mm, finite,
        /// strictly increasing, at least one; copied). <paramref name="options"/>
        /// (null for the defaults) is read for the flat_* keys and not kept.
        /// <see cref="InvalidArgumentException"/> for bad positions or
        /// FlatUpdateInterval &gt; FlatWindowLength.</summary>
        public unsafe Flatness(double[] fiberX, FlatlineOptions? options = null)
        {
            if (fiberX == null)
                throw new ArgumentNullException(nameof(fiberX));
            if (fiberX.Length == 0)
                throw new ArgumentException("fiberX is empty: at least one fiber", nameof(fiberX));
            using (var scope = FlatlineOptions.Borrow(options))
            fixed (double* px = fiberX)
            {
                FlatlineNative.flt_flatness_create((ulong)fiberX.Length, px, scope.Handle, out handle);
            }
            Init(options, out zoneLeftX, out zoneCentreX, out zoneFiberCount);
        }

        /// <summary>Metrics on the fiber grid of <paramref name="calibration"/>,
        /// which the object holds.</summary>
        public Flatness(Calibration calibration, FlatlineOptions? options = null)
        {
            if (calibration == null)
                throw new ArgumentNullException(nameof(calibration));
            using (var scope = FlatlineOptions.Borrow(options))
            {
                FlatlineNative.flt_flatness_create_from_calib(calibration.LiveHandle, scope.Handle, out handle);
            }
            Calibration = calibration;
            Init(options, out zoneLeftX, out zoneCentreX, out zoneFiberCount);
        }

        /// <summary>The calibration the metrics were created from, else null.</summary>
        public Calibration? Calibration { get; }
        public int Fibers { get; private set; }
        public int Zones { get; private set; }
        /// <summary>Left edge of each zone, mm (a copy).</summary>
        public double[] ZoneLeftX => (double[])zoneLeftX.Clone();
        /// <summary>Middle of each zone, mm (a copy).</summary>
        public double[] ZoneCentreX => (double[])zoneCentreX.Clone();
        /// <summary>Fibers in each zone (a copy).</summary>
        public int[] ZoneFiberCount => (int[])zoneFiberCount.Clone();

        /// <summary>The C library's lower-case name of a shape class.</summary>
        public static string ShapeName(ShapeClass shape)
        {
            NativeLoader.EnsureLoaded();
            return FlatlineNative.flt_shape_string((int)shape);
        }

        /// <summary>Evaluates one window from whole-sheet rows and returns its
        /// results. Independent of the streaming state.
        /// <see cref="InvalidArgumentException"/> (keeping the previous
        /// results) for fewer than 2 rows, non-increasing s, a window shorter
        /// than FlatMinLength or no fiber with enough usable data.</summary>
        public unsafe FlatnessResult Evaluate(double[] s, double[,] z, byte[,]? flags = null)
        {
            var live = LiveHandle;
            int rows = CheckRows(s, z, flags);
            fixed (double* ps = s, pz = z)
            fixed (byte* pf = flags)
            {
                FlatlineNative.flt_flatness_evaluate(live, (ulong)rows, (ulong)Fibers, ps, pz, pf);
            }
            return Result();
        }

        /// <summary>As <see cref="Evaluate"/>, with the strip's edges per row
        /// (flt_flatness_evaluate_strip): <paramref name="leftMm"/> and
        /// <paramref name="rightMm"/> [rows] in sensor x, mm, NaN where
        /// unknown (<see cref="Extractor.Strip"/> with laser 2 gives them),
        /// or null: unknown. Where the edges are known the window is measured
        /// on the strip (<see cref="FlatnessResult.Strip"/>).</summary>
        public unsafe FlatnessResult EvaluateStrip(double[] s, double[,] z, byte[,]? flags, double[]? leftMm,
                                                   double[]? rightMm)
        {
            var live = LiveHandle;
            int rows = CheckRows(s, z, flags);
            CheckEdges(leftMm, rightMm, rows);
            fixed (double* ps = s, pz = z, pl = leftMm, pr = rightMm)
            fixed (byte* pf = flags)
            {
                FlatlineNative.flt_flatness_evaluate_strip(live, (ulong)rows, (ulong)Fibers, ps, pz, pf, pl, pr);
            }
            return Result();
        }

        /// <summary>As <see cref="Push"/>, with the strip's edges per row (as
        /// in <see cref="EvaluateStrip"/>; indexed like s).</summary>
        public unsafe FlatnessPush PushStrip(double[] s, double[,] z, byte[,]? flags, double[]? leftMm,
                                             double[]? rightMm, int firstRow = 0, int rows = -1)
        {
            var live = LiveHandle;
            int total = CheckRows(s, z, flags);
            CheckEdges(leftMm, rightMm, total);
            if (firstRow < 0 || firstRow > total)
                throw new ArgumentOutOfRangeException(nameof(firstRow), firstRow, $"firstRow must be in 0 .. {total}");
            if (rows == -1)
                rows = total - firstRow;
            if (rows < 0 || rows > total - firstRow)
                throw new ArgumentOutOfRangeException(nameof(rows), rows,
                                                      $"rows must be in 0 .. {total - firstRow} (from row {firstRow})");
            ulong consumed = 0;
            int evaluated = 0;
            long offset = (long)firstRow * Fibers;
            fixed (double* ps = s, pz = z, pl = leftMm, pr = rightMm)
            fixed (byte* pf = flags)
            {
                FlatlineNative.flt_flatness_push_strip(live, (ulong)rows, (ulong)Fibers, ps + firstRow, pz + offset,
                                                       pf == null ? null : pf + offset,
                                                       pl == null ? null : pl + firstRow,
                                                       pr == null ? null : pr + firstRow, &consumed, &evaluated);
            }
            return new FlatnessPush((int)consumed, evaluated != 0);
        }

        /// <summary>Streams rows <paramref name="firstRow"/> ..
        /// <paramref name="firstRow"/> + <paramref name="rows"/> - 1 (all the
        /// rest when rows is -1) of s, z and flags; s continues to increase
        /// across calls. Stops after a window completes: when
        /// <see cref="FlatnessPush.Evaluated"/>, read <see cref="Result"/> and
        /// call again from firstRow + Consumed. <see cref="BufferFullException"/>
        /// when a window would hold more than FlatRowCapacity rows.</summary>
        public unsafe FlatnessPush Push(double[] s, double[,] z, byte[,]? flags = null, int firstRow = 0, int rows = -1)
        {
            var live = LiveHandle;
            int total = CheckRows(s, z, flags);
            if (firstRow < 0 || firstRow > total)
                throw new ArgumentOutOfRangeException(nameof(firstRow), firstRow, $"firstRow must be in 0 .. {total}");
            if (rows == -1)
                rows = total - firstRow;
            if (rows < 0 || rows > total - firstRow)
                throw new ArgumentOutOfRangeException(nameof(rows), rows,
                                                      $"rows must be in 0 .. {total - firstRow} (from row {firstRow})");
            ulong consumed = 0;
            int evaluated = 0;
            long offset = (long)firstRow * Fibers;
            fixed (double* ps = s, pz = z)
            fixed (byte* pf = flags)
            {
                FlatlineNative.flt_flatness_push(live, (ulong)rows, (ulong)Fibers, ps + firstRow, pz + offset,
                                                 pf == null ? null : pf + offset, &consumed, &evaluated);
            }
            return new FlatnessPush((int)consumed, evaluated != 0);
        }

        /// <summary>Ends the current sheet: evaluates the rows since the
        /// current window's start as one window and returns true, or returns
        /// false when fewer than 2 rows are pending. The next row pushed
        /// starts a new grid.</summary>
        public unsafe bool Finish()
        {
            int evaluated = 0;
            FlatlineNative.flt_flatness_finish(LiveHandle, &evaluated);
            return evaluated != 0;
        }

        /// <summary>Drops the pending rows and restarts the window grid; the
        /// last results stay.</summary>
        public void Reset() => FlatlineNative.flt_flatness_reset(LiveHandle);

        /// <summary>The results of the last evaluated window (new arrays).
        /// <see cref="FlatlineStateException"/> before the first window.</summary>
        public unsafe FlatnessResult Result()
        {
            var live = LiveHandle;
            double sFirst, sLast, confidence, bow, crossbow;
            uint windowFlags, components;
            ulong index;
            int shape;
            FlatlineNative.flt_flatness_window(live, &sFirst, &sLast, out UIntPtr rows, &windowFlags, &index);
            var fibers = new FiberResults(Fibers);
            fixed (double* pl = fibers.ArcLength, pi = fibers.IUnits, ph = fibers.WaveHeight,
                   pp = fibers.WavePeriod, pst = fibers.SteepnessPercent)
            fixed (FiberFlags* pf = fibers.Flags)
            {
                FlatlineNative.flt_flatness_fiber_results(live, (ulong)Fibers, pl, pi, ph, pp, pst, (byte*)pf);
            }
            var zoneIUnits = new double[Zones];
            var zoneFlags = new ZoneFlags[Zones];
            fixed (double* pz = zoneIUnits)
            fixed (ZoneFlags* pf = zoneFlags)
            {
                FlatlineNative.flt_flatness_zone_results(live, (ulong)Zones, pz, (byte*)pf);
            }
            FlatlineNative.flt_flatness_shape(live, &shape, &confidence, &components, &bow, &crossbow);
            var width = new double[3];
            var centre = new double[3];
            var fiberStrip = new double[Fibers];
            var fiberSensor = new double[Fibers];
            var zoneStrip = new double[Zones];
            var zoneSensor = new double[Zones];
            var zoneWidth = new double[Zones];
            var zoneCount = new ulong[Zones];
            fixed (double* pw = width, pc = centre, pfs = fiberStrip, pfx = fiberSensor, pzs = zoneStrip,
                   pzx = zoneSensor, pzw = zoneWidth)
            fixed (ulong* pzc = zoneCount)
            {
                FlatlineNative.flt_flatness_strip(live, pw, pc);
                FlatlineNative.flt_flatness_fiber_positions(live, (ulong)Fibers, pfs, pfx);
                FlatlineNative.flt_flatness_zone_positions(live, (ulong)Zones, pzs, pzx, pzw, pzc);
            }
            var counts = new int[Zones];
            for (int j = 0; j < Zones; ++j)
                counts[j] = (int)zoneCount[j];
            var strip = new StripWindow(((WindowFlags)windowFlags & WindowFlags.OnStrip) != 0, width, centre,
                                        fiberStrip, fiberSensor, zoneStrip, zoneSensor, zoneWidth, counts);
            return new FlatnessResult(
                new FlatnessWindow(sFirst, sLast, (int)rows.ToUInt64(), (WindowFlags)windowFlags, (long)index),
                fibers,
                new ZoneResults(zoneIUnits, zoneFlags, ZoneLeftX, ZoneCentreX, ZoneFiberCount),
                new ShapeResult((ShapeClass)shape, confidence, (ShapeComponents)components, bow, crossbow),
                strip);
        }

        /// <summary>Frees the native metrics now. Further calls throw
        /// <see cref="ObjectDisposedException"/>; a second Dispose does nothing.
        /// A calibration stays the caller's.</summary>
        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }

        private FlatnessHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(Flatness));
                return handle;
            }
        }

        private unsafe void Init(FlatlineOptions? options, out double[] leftX, out double[] centreX, out int[] fiberCount)
        {
            FlatlineNative.flt_flatness_fibers(handle, out UIntPtr fibers);
            FlatlineNative.flt_flatness_zones(handle, out UIntPtr zones);
            Fibers = checked((int)fibers.ToUInt64());
            Zones = checked((int)zones.ToUInt64());
            leftX = new double[Zones];
            centreX = new double[Zones];
            var counts = new ulong[Zones];
            fixed (double* pl = leftX, pc = centreX)
            fixed (ulong* pn = counts)
            {
                FlatlineNative.flt_flatness_zone_layout(handle, (ulong)Zones, pl, pc, pn);
            }
            fiberCount = Array.ConvertAll(counts, n => (int)n);
            handle.Track(NativeBytes(options != null ? options.FlatRowCapacity : DefaultRowCapacity));
        }

        private static void CheckEdges(double[]? leftMm, double[]? rightMm, int rows)
        {
            if (leftMm != null)
                Shapes.Check(leftMm, rows, nameof(leftMm));
            if (rightMm != null)
                Shapes.Check(rightMm, rows, nameof(rightMm));
        }

        private int CheckRows(double[] s, double[,] z, byte[,]? flags)
        {
            if (s == null)
                throw new ArgumentNullException(nameof(s));
            Shapes.Check(z, s.Length, Fibers, nameof(z));
            if (flags != null)
                Shapes.Check(flags, s.Length, Fibers, nameof(flags));
            return s.Length;
        }

        /// <summary>The native memory held (flatness.h: a window of
        /// flat_row_capacity rows at 9 bytes per row and fiber, plus per
        /// fiber results and scratch), reported to the GC as memory pressure.</summary>
        private long NativeBytes(int rowCapacity) => 9L * rowCapacity * Fibers + 128L * Fibers + 64L * Zones;

        /// <summary>flat_row_capacity's default (lib/core/options.cpp).</summary>
        private const int DefaultRowCapacity = 4096;
    }
}
