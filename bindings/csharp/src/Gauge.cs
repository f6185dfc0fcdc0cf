// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Concurrent;
using System.Collections.Generic;
using System.Runtime.CompilerServices;
using System.Runtime.InteropServices;
using System.Threading;
using System.Threading.Tasks;

namespace Flatline
{
    /// <summary>How a sheet began and ended, and which of its values are NaN
    /// (FLT_SHEET_FLAG_*).</summary>
    [Flags]
    public enum SheetFlags : uint
    {
        None = 0,
        /// <summary>Starts at its strip's head, not at a cut.</summary>
        Head = FlatlineNative.FLT_SHEET_FLAG_HEAD,
        /// <summary>Ends at its strip's tail (the strip left the sensor).</summary>
        Tail = FlatlineNative.FLT_SHEET_FLAG_TAIL,
        /// <summary>Ended by <see cref="Gauge.Flush"/> (the end of the input).</summary>
        Flushed = FlatlineNative.FLT_SHEET_FLAG_FLUSHED,
        /// <summary>Ended at GaugeMaxSheetLength: no cut came.</summary>
        Split = FlatlineNative.FLT_SHEET_FLAG_SPLIT,
        /// <summary>Ended because the encoder reversed or jumped: a new strip began.</summary>
        NewStrip = FlatlineNative.FLT_SHEET_FLAG_NEW_STRIP,
        /// <summary>The strip's edges are unknown: the Strip* values are NaN.</summary>
        NoEdges = FlatlineNative.FLT_SHEET_FLAG_NO_EDGES,
        /// <summary>No fiber has a wave: the Wave* values are NaN.</summary>
        NoWave = FlatlineNative.FLT_SHEET_FLAG_NO_WAVE,
        /// <summary>No row: every result is NaN and flagged.</summary>
        Empty = FlatlineNative.FLT_SHEET_FLAG_EMPTY,
        /// <summary>Its coverage is below GaugeMinCoverage: its shape and
        /// verdict are "not judged".</summary>
        Incomplete = FlatlineNative.FLT_SHEET_FLAG_INCOMPLETE,
        /// <summary>It lost rows: frames dropped, missing by the encoder, or
        /// lost lines.</summary>
        LostRows = FlatlineNative.FLT_SHEET_FLAG_LOST_ROWS,
        /// <summary>An early answer (GaugeProvisionalMm): its last rows are
        /// estimates made before they were final; the final sheet with the
        /// same id follows. Not counted, not archived, not in the coil's
        /// statistics.</summary>
        Provisional = FlatlineNative.FLT_SHEET_FLAG_PROVISIONAL,
    }

    /// <summary>What a full frame queue does (the option gauge_overflow).</summary>
    public enum GaugeOverflow
    {
        /// <summary>Drop the frame, count it and flag its sheet.</summary>
        Drop = NativeGaugeOverflow.FLT_GAUGE_OVERFLOW_DROP,
        /// <summary>The thread that delivers the frame waits for room.</summary>
        Wait = NativeGaugeOverflow.FLT_GAUGE_OVERFLOW_WAIT,
        /// <summary>Wait for pushed frames and an attached image sequence or
        /// simulator; drop for an attached camera (the default).</summary>
        Auto = NativeGaugeOverflow.FLT_GAUGE_OVERFLOW_AUTO,
    }

    /// <summary>The width that chooses a rule's band (<see cref="Gauge.SetRules"/>):
    /// a nominal width, or each sheet's measured strip width.</summary>
    public readonly struct SheetWidth : IEquatable<SheetWidth>
    {
        private SheetWidth(double mm)
        {
            Mm = mm;
        }

        /// <summary>Each sheet's measured strip width (<see cref="Sheet.StripWidthMm"/>).</summary>
        public static SheetWidth Measured => new SheetWidth(FlatlineNative.FLT_GAUGE_WIDTH_MEASURED);

        /// <summary>A nominal width, mm (&gt; 0).</summary>
        public static SheetWidth Nominal(double mm)
        {
            if (!(mm > 0))
                throw new ArgumentOutOfRangeException(nameof(mm), mm, "a nominal width is > 0 mm; SheetWidth.Measured for the measured one");
            return new SheetWidth(mm);
        }

        /// <summary>The width in mm, or 0 for <see cref="Measured"/>.</summary>
        public double Mm { get; }

        /// <summary>True for <see cref="Measured"/>.</summary>
        public bool IsMeasured => Mm == FlatlineNative.FLT_GAUGE_WIDTH_MEASURED;

        public bool Equals(SheetWidth other) => Mm.Equals(other.Mm);
        public override bool Equals(object? obj) => obj is SheetWidth other && Equals(other);
        public override int GetHashCode() => Mm.GetHashCode();
        public override string ToString() => IsMeasured ? "measured" : $"{Mm} mm";
    }

    /// <summary>One rule's statistics over a coil (flt_gauge_coil_stats).</summary>
    public sealed class RuleStats
    {
        internal RuleStats(int rule, double[] v)
        {
            Rule = rule;
            Passed = (long)v[(int)NativeCoilValue.FLT_COIL_RULE_PASSED];
            Failed = (long)v[(int)NativeCoilValue.FLT_COIL_RULE_FAILED];
            NoBand = (long)v[(int)NativeCoilValue.FLT_COIL_RULE_NO_BAND];
            NotMeasured = (long)v[(int)NativeCoilValue.FLT_COIL_RULE_NOT_MEASURED];
            NotJudged = (long)v[(int)NativeCoilValue.FLT_COIL_RULE_NOT_JUDGED];
            WorstMin = v[(int)NativeCoilValue.FLT_COIL_WORST_MIN];
            WorstMax = v[(int)NativeCoilValue.FLT_COIL_WORST_MAX];
            WorstMean = v[(int)NativeCoilValue.FLT_COIL_WORST_MEAN];
            WorstSheet = v[(int)NativeCoilValue.FLT_COIL_WORST_SHEET];
            WorstXMm = v[(int)NativeCoilValue.FLT_COIL_WORST_X];
            WorstSMm = v[(int)NativeCoilValue.FLT_COIL_WORST_S];
            var histogram = new long[FlatlineNative.FLT_COIL_HISTOGRAM_BINS];
            for (int i = 0; i < histogram.Length; ++i)
                histogram[i] = (long)v[(int)NativeCoilValue.FLT_COIL_HISTOGRAM + i];
            Histogram = Array.AsReadOnly(histogram);
        }

        /// <summary>The rule's index in its rule set.</summary>
        public int Rule { get; }
        /// <summary>Sheets that passed it, failed it, that none of its bands
        /// covers, and that its measure was missing on.</summary>
        public long Passed { get; }
        public long Failed { get; }
        public long NoBand { get; }
        public long NotMeasured { get; }
        /// <summary>Incomplete sheets, which no rule judged.</summary>
        public long NotJudged { get; }
        /// <summary>The worst values of the sheets measured: smallest,
        /// largest, mean (NaN when none was).</summary>
        public double WorstMin { get; }
        public double WorstMax { get; }
        public double WorstMean { get; }
        /// <summary>Where the largest is: the sheet's id (NaN: none), x and s, mm.</summary>
        public double WorstSheet { get; }
        public double WorstXMm { get; }
        public double WorstSMm { get; }
        /// <summary>Sheets by worst / limit: bin i counts (i/10, (i+1)/10]
        /// (bin 0 from 0, the last everything above 1.9): bins 0-9 passed,
        /// 10-19 failed.</summary>
        public IReadOnlyList<long> Histogram { get; }
    }

    /// <summary>A coil's verdict statistics (flt_gauge_coil_stats).</summary>
    public sealed class CoilStats
    {
        internal CoilStats(double[] first, IReadOnlyList<RuleStats> rules)
        {
            Coil = (long)first[(int)NativeCoilValue.FLT_COIL_NUMBER];
            Sheets = (long)first[(int)NativeCoilValue.FLT_COIL_SHEETS];
            Passed = (long)first[(int)NativeCoilValue.FLT_COIL_SHEETS_PASSED];
            Failed = (long)first[(int)NativeCoilValue.FLT_COIL_SHEETS_FAILED];
            NotJudged = (long)first[(int)NativeCoilValue.FLT_COIL_SHEETS_NOT_JUDGED];
            Finished = first[(int)NativeCoilValue.FLT_COIL_FINISHED] != 0;
            Rules = rules;
        }

        /// <summary>The coil's number (0: no sheet judged yet).</summary>
        public long Coil { get; }
        /// <summary>Sheets evaluated under the rules (Passed + Failed +
        /// NotJudged); those every rule judged and passed; those that failed
        /// one or more; those no rule failed that some rule could not judge
        /// (no band, a missing measure, incomplete): never counted as passed.</summary>
        public long Sheets { get; }
        public long Passed { get; }
        public long Failed { get; }
        public long NotJudged { get; }
        /// <summary>Sheets judged: <see cref="Passed"/> + <see cref="Failed"/>.</summary>
        public long Judged => Passed + Failed;
        /// <summary>True once the coil's last sheet was judged.</summary>
        public bool Finished { get; }
        /// <summary>Per rule, in rule order.</summary>
        public IReadOnlyList<RuleStats> Rules { get; }
    }

    /// <summary>
    /// One measured sheet, copied out of the library (it stays valid for as
    /// long as it is referenced). A NaN value always comes with its flag:
    /// <see cref="Flags"/> for the strip edges and the wave,
    /// <see cref="WindowFlags"/> for bow and crossbow, the fiber and zone
    /// flags for the arrays.
    /// </summary>
    public sealed class Sheet
    {
        private readonly double[] values;

        private Sheet(double[] values)
        {
            this.values = values;
        }

        /// <summary>Any scalar result by key (later library versions add keys).</summary>
        public double Value(SheetValue key) => values[(int)key];

        /// <summary>The sheet's number along the gauge's life, 1, 2, ...</summary>
        public long Id => (long)Value(SheetValue.Id);
        /// <summary>The number of its strip (coil), 1, 2, ...</summary>
        public long Coil => (long)Value(SheetValue.Coil);
        /// <summary>Its number within the coil, 1, 2, ...</summary>
        public long Index => (long)Value(SheetValue.Index);
        /// <summary>Where it starts along the strip, mm (a cut, or its strip's head).</summary>
        public double SStartMm => Value(SheetValue.SStart);
        /// <summary>Where it ends, mm (a cut, the tail, a split).</summary>
        public double SEndMm => Value(SheetValue.SEnd);
        /// <summary>Rows (frames) in the sheet.</summary>
        public int Rows => (int)Value(SheetValue.Rows);
        /// <summary>s of its first and last row, mm (NaN with <see cref="SheetFlags.Empty"/>).</summary>
        public double SFirstMm => Value(SheetValue.SFirst);
        public double SLastMm => Value(SheetValue.SLast);
        /// <summary>The strip's edges, width and centre across the sensor, mm
        /// (from the extractor's edges where it saw them: WindowFlags.OnStrip).</summary>
        public double StripLeftMm => Value(SheetValue.StripLeft);
        public double StripRightMm => Value(SheetValue.StripRight);
        public double StripWidthMm => Value(SheetValue.StripWidth);
        public double StripCentreMm => Value(SheetValue.StripCentre);
        /// <summary>The strip's width and centre over the sheet's rows:
        /// smallest and largest, mm (a strip that narrows or wanders).</summary>
        public double StripWidthMinMm => Value(SheetValue.StripWidthMin);
        public double StripWidthMaxMm => Value(SheetValue.StripWidthMax);
        public double StripCentreMinMm => Value(SheetValue.StripCentreMin);
        public double StripCentreMaxMm => Value(SheetValue.StripCentreMax);
        /// <summary>The shape class, its confidence in [0, 1] and its components.</summary>
        public ShapeClass Shape => (ShapeClass)(int)Value(SheetValue.Shape);
        /// <summary>The C library's name of the class, e.g. "centre buckle".</summary>
        public string ShapeName => Flatness.ShapeName(Shape);
        public double Confidence => Value(SheetValue.Confidence);
        public ShapeComponents Components => (ShapeComponents)(uint)Value(SheetValue.Components);
        /// <summary>Bow (coil set) and crossbow sagittas, mm.</summary>
        public double BowMm => Value(SheetValue.Bow);
        public double CrossbowMm => Value(SheetValue.Crossbow);
        /// <summary>The largest wave over the fibers: peak-to-peak height (mm),
        /// period (mm), steepness (%), and the x of its fiber (mm).</summary>
        public double WaveHeightMm => Value(SheetValue.WaveHeight);
        public double WavePeriodMm => Value(SheetValue.WavePeriod);
        public double WaveSteepnessPercent => Value(SheetValue.WaveSteepness);
        public double WaveXMm => Value(SheetValue.WaveX);
        /// <summary>The largest zone I-Units.</summary>
        public double MaxIUnits => Value(SheetValue.MaxIUnits);
        public SheetFlags Flags => (SheetFlags)(uint)Value(SheetValue.Flags);
        public WindowFlags WindowFlags => (WindowFlags)(uint)Value(SheetValue.WindowFlags);
        /// <summary>Frames measured (its rows), skipped (line stops, short
        /// reversals), dropped (a full queue); saturated peaks; invalid samples.</summary>
        public long Frames => (long)Value(SheetValue.Frames);
        public long Skipped => (long)Value(SheetValue.Skipped);
        public long Dropped => (long)Value(SheetValue.Dropped);
        public long Saturated => (long)Value(SheetValue.Saturated);
        public long Invalid => (long)Value(SheetValue.Invalid);
        /// <summary>Strip the reconstructor had taken beyond <see cref="SEndMm"/>
        /// when the sheet was finished, mm.</summary>
        public double LookaheadMm => Value(SheetValue.Lookahead);
        /// <summary><see cref="LookaheadMm"/> in seconds, at the line speed
        /// the frames' times show (0 when the sheet waited for no strip).</summary>
        public double LatencySeconds => Value(SheetValue.Latency);
        /// <summary>When the strip at <see cref="SEndMm"/> passed the sensor:
        /// UTC (the recording's time on a replay). <see cref="FinishedTime"/>
        /// less this is the whole wait on a live line.</summary>
        public DateTime CutTime =>
            new DateTime(1970, 1, 1, 0, 0, 0, DateTimeKind.Utc).AddTicks((long)(Value(SheetValue.CutTime) * TimeSpan.TicksPerSecond));
        /// <summary>Rows measured over the rows its length should hold, 0..1;
        /// below GaugeMinCoverage the sheet is <see cref="Incomplete"/>.</summary>
        public double Coverage => Value(SheetValue.Coverage);
        /// <summary>Too many rows are missing for a class or a verdict: its
        /// <see cref="Shape"/> is <see cref="ShapeClass.NotJudged"/> and its
        /// <see cref="VerdictState"/> <see cref="Flatline.VerdictState.NotJudged"/>.</summary>
        public bool Incomplete => (Flags & SheetFlags.Incomplete) != 0;
        /// <summary>An early answer: its values and verdict may still change,
        /// and the final sheet with the same <see cref="Id"/> follows.</summary>
        public bool Provisional => (Flags & SheetFlags.Provisional) != 0;
        /// <summary>The rows its length should hold (rows + dropped + missing),
        /// those that measured the strip, lost lines (rows inside the strip
        /// whose frame did not show it), and frames missing by the encoder.</summary>
        public long RowsExpected => (long)Value(SheetValue.RowsExpected);
        public long RowsMeasured => (long)Value(SheetValue.RowsMeasured);
        public long LostLines => (long)Value(SheetValue.LostLines);
        public long Missing => (long)Value(SheetValue.Missing);
        /// <summary>Laser peaks on the strip (the denominator of <see cref="Saturated"/>).</summary>
        public long Peaks => (long)Value(SheetValue.Peaks);
        /// <summary>The whole sheet's verdict: Fail when a rule failed, Pass
        /// when every rule was judged and passed, else NotJudged (no rules, a
        /// rule that could not judge it, an incomplete sheet): never a pass.</summary>
        public VerdictState VerdictState => (VerdictState)(int)Value(SheetValue.Verdict);

        /// <summary>Per fiber [fibers]: x (mm), I-Units, arc length (mm), the
        /// largest wave's height (mm), period (mm) and steepness (%), flags.</summary>
        public double[] FiberX { get; private set; } = Array.Empty<double>();
        public double[] FiberIUnits { get; private set; } = Array.Empty<double>();
        public double[] FiberArcLengthMm { get; private set; } = Array.Empty<double>();
        public double[] FiberWaveHeightMm { get; private set; } = Array.Empty<double>();
        public double[] FiberWavePeriodMm { get; private set; } = Array.Empty<double>();
        public double[] FiberSteepnessPercent { get; private set; } = Array.Empty<double>();
        public FiberFlags[] FiberFlags { get; private set; } = Array.Empty<FiberFlags>();
        /// <summary>Per zone [zones]: centre x (mm), I-Units, flags.</summary>
        public double[] ZoneCentreX { get; private set; } = Array.Empty<double>();
        /// <summary>Strip coordinates (mm from the strip's centre line towards
        /// the operator side) of each fiber [fibers] and zone centre [zones];
        /// NaN where its flags say it has no data.</summary>
        public double[] FiberStripX { get; private set; } = Array.Empty<double>();
        public double[] ZoneStripX { get; private set; } = Array.Empty<double>();
        public double[] ZoneIUnits { get; private set; } = Array.Empty<double>();
        public ZoneFlags[] ZoneFlags { get; private set; } = Array.Empty<ZoneFlags>();

        /// <summary>With GaugeKeepMaps >= 1: the rows' positions [rows] (mm),
        /// reconstructed heights [rows, fibers] (mm) and their flags; null
        /// otherwise.</summary>
        public double[]? S { get; private set; }
        public double[,]? Z { get; private set; }
        public ReconFlags[,]? ZFlags { get; private set; }
        /// <summary>With GaugeKeepMaps = 2: the measured heights [rows,
        /// fibers] (mm, NaN where invalid); null otherwise.</summary>
        public double[,]? Measured { get; private set; }

        /// <summary>Its verdict, one result per rule of the rules it was
        /// judged by (<see cref="Gauge.SetRules"/>); null when the gauge had none.</summary>
        public IReadOnlyList<RuleResult>? Verdict { get; private set; }
        /// <summary>The number of rules it failed (0 without rules).</summary>
        public int FailedRules => (int)Value(SheetValue.RulesFailed);
        /// <summary>Its coil's identity (<see cref="Gauge.SetCoil"/>); null
        /// when the coil had none.</summary>
        public CoilInfo? CoilInfo { get; private set; }
        /// <summary>The notes given while its rows were taken (<see cref="Gauge.Note"/>).</summary>
        public IReadOnlyList<SheetNote> Notes { get; private set; } = Array.Empty<SheetNote>();
        /// <summary>When it was finished: host UTC.</summary>
        public DateTime FinishedTime =>
            new DateTime(1970, 1, 1, 0, 0, 0, DateTimeKind.Utc).AddTicks((long)(Value(SheetValue.FinishedTime) * TimeSpan.TicksPerSecond));

        internal static unsafe Sheet Read(IntPtr sheet, int maps)
        {
            int count = Tables.SheetValueCount;
            var values = new double[count];
            for (int key = 0; key < count; ++key)
            {
                FlatlineNative.flt_cs_sheet_get(sheet, key, out double v);
                values[key] = v;
            }
            var result = new Sheet(values);
            int fibers = (int)values[(int)SheetValue.Fibers], zones = (int)values[(int)SheetValue.Zones];
            double[] Values(NativeSheetArray key, int n)
            {
                var a = new double[n];
                fixed (double* pa = a)
                    FlatlineNative.flt_cs_sheet_get_array(sheet, (int)key, (ulong)n, pa);
                return a;
            }
            result.FiberX = Values(NativeSheetArray.FLT_SHEET_FIBER_X, fibers);
            result.FiberIUnits = Values(NativeSheetArray.FLT_SHEET_FIBER_I_UNITS, fibers);
            result.FiberArcLengthMm = Values(NativeSheetArray.FLT_SHEET_FIBER_ARC_LENGTH, fibers);
            result.FiberWaveHeightMm = Values(NativeSheetArray.FLT_SHEET_FIBER_WAVE_HEIGHT, fibers);
            result.FiberWavePeriodMm = Values(NativeSheetArray.FLT_SHEET_FIBER_WAVE_PERIOD, fibers);
            result.FiberSteepnessPercent = Values(NativeSheetArray.FLT_SHEET_FIBER_STEEPNESS, fibers);
            var fiberFlags = Values(NativeSheetArray.FLT_SHEET_FIBER_FLAGS, fibers);
            result.FiberFlags = new FiberFlags[fibers];
            for (int k = 0; k < fibers; ++k)
                result.FiberFlags[k] = (FiberFlags)(byte)fiberFlags[k];
            result.ZoneCentreX = Values(NativeSheetArray.FLT_SHEET_ZONE_CENTRE_X, zones);
            result.ZoneIUnits = Values(NativeSheetArray.FLT_SHEET_ZONE_I_UNITS, zones);
            result.FiberStripX = Values(NativeSheetArray.FLT_SHEET_FIBER_STRIP_X, fibers);
            result.ZoneStripX = Values(NativeSheetArray.FLT_SHEET_ZONE_STRIP_X, zones);
            var zoneFlags = Values(NativeSheetArray.FLT_SHEET_ZONE_FLAGS, zones);
            result.ZoneFlags = new ZoneFlags[zones];
            for (int j = 0; j < zones; ++j)
                result.ZoneFlags[j] = (ZoneFlags)(byte)zoneFlags[j];
            int rows = result.Rows;
            if (maps >= 1)
            {
                var s = new double[rows];
                var z = new double[rows, fibers];
                var flags = new ReconFlags[rows, fibers];
                fixed (double* ps = s, pz = z)
                fixed (ReconFlags* pf = flags)
                    FlatlineNative.flt_cs_sheet_height_map(sheet, (ulong)rows, (ulong)fibers, ps, pz, (byte*)pf);
                result.S = s;
                result.Z = z;
                result.ZFlags = flags;
            }
            if (maps >= 2)
            {
                var measured = new double[rows, fibers];
                fixed (double* pm = measured)
                    FlatlineNative.flt_cs_sheet_measured_map(sheet, (ulong)rows, (ulong)fibers, pm);
                result.Measured = measured;
            }
            int rules = (int)values[(int)SheetValue.Rules];
            if (rules > 0)
            {
                var verdict = new List<RuleResult>(rules);
                for (int i = 0; i < rules; ++i)
                {
                    int measure;
                    double length;
                    FlatlineNative.flt_cs_sheet_rule(sheet, (ulong)i, out IntPtr name, &measure, &length);
                    var rule = new ToleranceRule(Utf8.Decode(name), (Measure)measure, length);
                    double Get(NativeVerdictValue key)
                    {
                        FlatlineNative.flt_cs_sheet_verdict_get(sheet, (ulong)i, (int)key, out double v);
                        return v;
                    }
                    verdict.Add(new RuleResult(rule, (VerdictState)(int)Get(NativeVerdictValue.FLT_VERDICT_STATE),
                                               Get(NativeVerdictValue.FLT_VERDICT_WORST),
                                               Get(NativeVerdictValue.FLT_VERDICT_LIMIT),
                                               Get(NativeVerdictValue.FLT_VERDICT_MARGIN),
                                               Get(NativeVerdictValue.FLT_VERDICT_X),
                                               Get(NativeVerdictValue.FLT_VERDICT_S),
                                               (int)Get(NativeVerdictValue.FLT_VERDICT_BAND)));
                }
                result.Verdict = verdict.AsReadOnly();
            }
            if (FlatlineNative.flt_cs_sheet_has_coil(sheet) != 0)
            {
                FlatlineNative.flt_cs_sheet_coil_copy(sheet, out CoilInfoHandle coil);
                using (coil)
                    result.CoilInfo = Flatline.CoilInfo.FromNative(coil);
            }
            FlatlineNative.flt_cs_sheet_note_count(sheet, out UIntPtr notes);
            var list = new List<SheetNote>();
            for (ulong i = 0; i < notes.ToUInt64(); ++i)
            {
                IntPtr kind, text;
                double at;
                FlatlineNative.flt_cs_sheet_note(sheet, i, &kind, &text, &at);
                list.Add(new SheetNote(Utf8.Decode(kind), Utf8.Decode(text), at));
            }
            result.Notes = list.AsReadOnly();
            return result;
        }

        // Invariant: the same text under every culture, as the C library writes numbers.
        public override string ToString() =>
            FormattableString.Invariant(
                $"sheet {Id} (coil {Coil}): {SStartMm:F0} .. {SEndMm:F0} mm, {Rows} rows, {ShapeName}, {MaxIUnits:F1} I-Units");
    }

    /// <summary>A note given with <see cref="Gauge.Note"/> (a leveler change, a remark).</summary>
    public sealed class SheetNote
    {
        internal SheetNote(string kind, string text, double sMm)
        {
            Kind = kind;
            Text = text;
            SMm = sMm;
        }

        /// <summary>What it is ("leveler").</summary>
        public string Kind { get; }
        /// <summary>What it says.</summary>
        public string Text { get; }
        /// <summary>Where it took effect along the strip, mm.</summary>
        public double SMm { get; }
        public override string ToString() => $"{Kind}: {Text}";
    }

    /// <summary>The sheet of a <see cref="Gauge.SheetFinished"/> event.</summary>
    public sealed class SheetEventArgs : EventArgs
    {
        internal SheetEventArgs(Sheet sheet) => Sheet = sheet;
        public Sheet Sheet { get; }
    }

    /// <summary>
    /// One handle that runs a line (flatline/gauge.h): camera frames (or
    /// profile rows) and the shear's cuts in, measured <see cref="Sheet"/>s
    /// out. Created from the sensor's finished calibration (frame size, laser
    /// spacing, fiber grid) and one options bag (the reconstructor's, the
    /// Extract*, Flat* and Gauge* keys; another component's is refused).
    /// </summary>
    /// <remarks>
    /// Frames go in with <see cref="Push(byte[,], double)"/> (copied), or
    /// from an attached <see cref="FrameSource"/> the gauge acquires on a
    /// thread of its own (<see cref="Attach"/>, <see cref="Start"/>,
    /// <see cref="Stop"/>). <see cref="Cut"/> tells where the shear cut,
    /// before or after the strip gets there; <see cref="Flush"/> ends the
    /// strip at the end of the input. Sheets come out in order: by polling
    /// (<see cref="NextSheet"/>), as the <see cref="SheetFinished"/> event,
    /// or as an <c>await foreach</c> over <see cref="SheetsAsync"/>. While an
    /// event handler or an enumeration is active the sheets go to them
    /// (raised on a gauge thread; a handler must not call Flush, Stop or
    /// Dispose of its gauge), and NextSheet throws
    /// <see cref="FlatlineStateException"/>. Frames come from one thread at a
    /// time; the other calls may come from any thread.
    /// </remarks>
    public sealed class Gauge : IDisposable
    {
        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        private delegate void NativeSheetCallback(IntPtr sheet, IntPtr user);

        private readonly GaugeHandle handle;
        private readonly NativeSheetCallback callback;  // kept alive while the gauge lives
        private readonly IntPtr callbackPointer;
        private readonly object sync = new object();            // handlers, channels, errors
        private readonly object registration = new object();    // the native callback's state
        private readonly object push = new object();            // the attached source
        private EventHandler<SheetEventArgs>? sheetFinished;
        private readonly List<SheetChannel> channels = new List<SheetChannel>();
        private bool callbackSet;
        private Exception? handlerError;
        private SourceHandle? attached;  // referenced (DangerousAddRef) while attached
        private RecorderHandle? attachedRecorder;  // likewise
        private ArchiveHandle? attachedArchive;    // likewise

        static Gauge() => NativeLoader.EnsureLoaded();

        /// <summary>A gauge for the sensor of <paramref name="calibration"/>
        /// (finished, else <see cref="FlatlineStateException"/>);
        /// <paramref name="options"/> (null for the defaults) is copied.
        /// <see cref="InvalidArgumentException"/> names an option a part
        /// refuses (or one of another component). Its worker threads start
        /// here.</summary>
        public Gauge(Calibration calibration, FlatlineOptions? options = null)
        {
            if (calibration == null)
                throw new ArgumentNullException(nameof(calibration));
            using (var scope = FlatlineOptions.Borrow(options))
            {
                FlatlineNative.flt_gauge_create(calibration.LiveHandle, scope.Handle, out handle);
            }
            Calibration = calibration;
            FrameWidth = calibration.FrameWidth;
            FrameHeight = calibration.FrameHeight;
            FlatlineNative.flt_gauge_get_option(handle, FlatlineOptions.Key("gauge_keep_maps"), out double maps);
            Maps = (int)maps;
            FlatlineNative.flt_gauge_get_option(handle, FlatlineOptions.Key("row_capacity"), out double rows);
            callback = OnSheet;
            callbackPointer = Marshal.GetFunctionPointerForDelegate(callback);
            // Its buffers, mostly the reconstructor's rows (9 bytes per row and fiber).
            handle.Track((long)(rows * calibration.FiberGrid.Count * 9));
        }

        /// <summary>The calibration the gauge was created from.</summary>
        public Calibration Calibration { get; }
        public int FrameWidth { get; }
        public int FrameHeight { get; }
        /// <summary>What each sheet keeps of its rows (GaugeKeepMaps).</summary>
        public int Maps { get; }

        /// <summary>The effective value of an option: the gauge's, and the
        /// reconstructor's as the gauge set them (laser_spacing from the
        /// calibration, row_capacity from its latency).</summary>
        public double GetOption(string name)
        {
            FlatlineNative.flt_gauge_get_option(LiveHandle, FlatlineOptions.Key(name), out double value);
            return value;
        }

        // ---- input ---------------------------------------------------------

        /// <summary>One Mono8 frame [FrameHeight, FrameWidth] taken at
        /// <paramref name="encoderMm"/> (mm); copied. Frames skipped (line
        /// stop, reversal) or dropped (a full queue) are counted, not thrown.</summary>
        public unsafe void Push(byte[,] frame, double encoderMm)
        {
            CheckFrame(frame);
            // One producer at a time: the library refuses a second thread
            // that pushes meanwhile, or a handler of this gauge's sheets
            // (FlatlineStateException), instead of waiting for it.
            ThrowHandlerError();
            fixed (byte* pf = frame)
                FlatlineNative.flt_gauge_push_frame(LiveHandle, pf, (int)PixelFormat.Mono8, (uint)FrameWidth,
                                                    (uint)FrameHeight, (ulong)FrameWidth, encoderMm);
        }

        /// <summary>One 16-bit frame of <paramref name="format"/> (Mono10, 12 or 16).</summary>
        public unsafe void Push(ushort[,] frame, PixelFormat format, double encoderMm)
        {
            if (format == PixelFormat.Mono8)
                throw new ArgumentException("a ushort[,] frame is Mono10, Mono12 or Mono16; pass Mono8 frames as byte[,]",
                                            nameof(format));
            CheckFrame(frame);
            ThrowHandlerError();
            fixed (ushort* pf = frame)
                FlatlineNative.flt_gauge_push_frame(LiveHandle, pf, (int)format, (uint)FrameWidth,
                                                    (uint)FrameHeight, (ulong)FrameWidth * 2, encoderMm);
        }

        /// <summary>A simulated frame, with its own format and encoder position.</summary>
        public void Push(SimulatedFrame frame)
        {
            if (frame == null)
                throw new ArgumentNullException(nameof(frame));
            if (frame.Pixels is byte[,] pixels8)
                Push(pixels8, frame.EncoderMm);
            else
                Push((ushort[,])frame.Pixels, frame.Format, frame.EncoderMm);
        }

        /// <summary>A frame from a <see cref="FrameSource"/>.</summary>
        public void Push(Frame frame)
        {
            if (frame == null)
                throw new ArgumentNullException(nameof(frame));
            if (frame.Pixels is byte[,] pixels8)
                Push(pixels8, frame.EncoderMm);
            else
                Push((ushort[,])frame.Pixels, frame.Format, frame.EncoderMm);
        }

        /// <summary>One profile row instead of a frame (a sensor that extracts
        /// its own profiles): heights (mm) and slopes (mm/mm) [fibers], valid
        /// [fibers] or null (then finite values are valid).</summary>
        public unsafe void PushRow(double encoderMm, double[] height, double[] slope, bool[]? valid = null)
        {
            if (height == null)
                throw new ArgumentNullException(nameof(height));
            if (slope == null)
                throw new ArgumentNullException(nameof(slope));
            Shapes.Check(slope, height.Length, nameof(slope));
            if (valid != null)
                Shapes.Check(valid, height.Length, nameof(valid));
            ThrowHandlerError();
            fixed (double* ph = height, pg = slope)
            fixed (bool* pv = valid)
                FlatlineNative.flt_gauge_push_row(LiveHandle, encoderMm, (ulong)height.Length, ph, pg, (byte*)pv);
        }

        /// <summary>The shear cut the strip at <paramref name="encoderMm"/>
        /// (the reading at which the cut line lies midway between the lasers),
        /// before or after the strip gets there; cuts come in increasing order.</summary>
        public void Cut(double encoderMm)
        {
            ThrowHandlerError();
            FlatlineNative.flt_gauge_cut(LiveHandle, encoderMm);
        }

        /// <summary>The end of the input: processes every frame pushed, ends
        /// the strip (its last sheet) and waits until that sheet is out.</summary>
        public void Flush()
        {
            ThrowHandlerError();
            FlatlineNative.flt_gauge_flush(LiveHandle);
            ThrowHandlerError();
        }

        // ---- acquisition ---------------------------------------------------

        /// <summary>Acquires from <paramref name="source"/> on <see cref="Start"/>
        /// (kept alive while attached; leave it alone meanwhile); null
        /// detaches. <see cref="FlatlineStateException"/> while acquiring.</summary>
        public void Attach(FrameSource? source)
        {
            var live = LiveHandle;
            lock (push)
            {
                SourceHandle? next = source?.LiveHandle;
                bool added = false;
                next?.DangerousAddRef(ref added);
                try
                {
                    if (next != null)
                        FlatlineNative.flt_gauge_attach_source(live, next);
                    else
                        FlatlineNative.flt_gauge_attach_source(live, new SourceHandle());
                }
                catch
                {
                    if (added)
                        next!.DangerousRelease();
                    throw;
                }
                attached?.DangerousRelease();
                attached = added ? next : null;
            }
        }

        // ---- the quality record ---------------------------------------------

        /// <summary>The coil the next strip is (or the strip under the sensor,
        /// when it has no identity yet): its sheets, statistics and verdicts
        /// carry it, and its nominal thickness and width, where given, choose
        /// the rule bands. Takes effect with the next frame; null: no identity.</summary>
        public void SetCoil(CoilInfo? coil)
        {
            var live = LiveHandle;
            if (coil == null)
            {
                FlatlineNative.flt_cs_gauge_clear_coil(live);
                return;
            }
            using (var h = coil.ToHandle())
                FlatlineNative.flt_gauge_set_coil(live, h);
        }

        /// <summary>The identity of the coil being measured (or, with
        /// <paramref name="last"/>, of the last finished one); null when it has none.</summary>
        public CoilInfo? CoilInfo(bool last = false)
        {
            var live = LiveHandle;
            try
            {
                FlatlineNative.flt_gauge_coil_info(live, last ? (int)NativeCoil.FLT_COIL_LAST
                                                              : (int)NativeCoil.FLT_COIL_CURRENT,
                                                   out CoilInfoHandle h);
                using (h)
                    return Flatline.CoilInfo.FromNative(h);
            }
            catch (NotFoundException)
            {
                return null;
            }
        }

        /// <summary>A note from the next frame on (a leveler change: kind
        /// "leveler"), given to the sheet whose rows begin there, recorded and archived.</summary>
        public void Note(string kind, string text)
        {
            if (kind == null)
                throw new ArgumentNullException(nameof(kind));
            if (text == null)
                throw new ArgumentNullException(nameof(text));
            FlatlineNative.flt_gauge_note(LiveHandle, kind, text);
        }

        /// <summary>Records the gauge's input from the next frame on (the
        /// recorder is kept alive while attached); null stops. Only while the
        /// gauge is idle (before the first frame, or after <see cref="Flush"/>).</summary>
        public void AttachRecorder(Recorder? recorder)
        {
            var live = LiveHandle;
            lock (push)
            {
                RecorderHandle? next = recorder?.LiveHandle;
                bool added = false;
                next?.DangerousAddRef(ref added);
                try
                {
                    if (next != null)
                        FlatlineNative.flt_gauge_attach_recorder(live, next);
                    else
                        FlatlineNative.flt_cs_gauge_detach_recorder(live);
                }
                catch
                {
                    if (added)
                        next!.DangerousRelease();
                    throw;
                }
                attachedRecorder?.DangerousRelease();
                attachedRecorder = added ? next : null;
            }
        }

        /// <summary>Archives every sheet finished from now on (the archive is
        /// kept alive while attached); null stops. Only while the gauge is idle.</summary>
        public void AttachArchive(Archive? archive)
        {
            var live = LiveHandle;
            lock (push)
            {
                ArchiveHandle? next = archive?.LiveHandle;
                bool added = false;
                next?.DangerousAddRef(ref added);
                try
                {
                    if (next != null)
                        FlatlineNative.flt_gauge_attach_archive(live, next);
                    else
                        FlatlineNative.flt_cs_gauge_detach_archive(live);
                }
                catch
                {
                    if (added)
                        next!.DangerousRelease();
                    throw;
                }
                attachedArchive?.DangerousRelease();
                attachedArchive = added ? next : null;
            }
        }

        /// <summary>Starts the attached source and the gauge's acquisition thread.</summary>
        public void Start() => FlatlineNative.flt_gauge_start(LiveHandle);

        /// <summary>Stops the acquisition and waits until its frames are
        /// processed (the strip stays open: <see cref="Flush"/> ends it).
        /// Throws the error that ended the acquisition by itself, e.g.
        /// <see cref="DeviceException"/> for an unplugged camera.</summary>
        public void Stop()
        {
            FlatlineNative.flt_gauge_stop(LiveHandle);
            ThrowHandlerError();
        }

        // ---- output --------------------------------------------------------

        /// <summary>The next finished sheet, waiting up to
        /// <paramref name="timeoutMs"/>; null if none came.
        /// <see cref="FlatlineStateException"/> while the sheets go to
        /// <see cref="SheetFinished"/> or <see cref="SheetsAsync"/>.</summary>
        public Sheet? NextSheet(int timeoutMs = 0)
        {
            if (timeoutMs < 0)
                throw new ArgumentOutOfRangeException(nameof(timeoutMs), timeoutMs, "must be >= 0");
            FlatlineNative.flt_gauge_next_sheet(LiveHandle, (uint)timeoutMs, out SheetHandle sheet);
            using (sheet)
            {
                if (sheet.IsInvalid)
                    return null;
                bool added = false;
                sheet.DangerousAddRef(ref added);
                try
                {
                    return Sheet.Read(sheet.DangerousGetHandle(), Maps);
                }
                finally
                {
                    if (added)
                        sheet.DangerousRelease();
                }
            }
        }

        /// <summary>Every sheet, in order, raised on a gauge thread (sheets
        /// already waiting are raised when the first handler is added). An
        /// exception a handler throws is thrown, wrapped, by the gauge's next
        /// Push, Cut, Flush or Stop.</summary>
        public event EventHandler<SheetEventArgs> SheetFinished
        {
            add
            {
                lock (sync)
                    sheetFinished += value;
                UpdateCallback();
            }
            remove
            {
                lock (sync)
                    sheetFinished -= value;
                UpdateCallback();
            }
        }

        /// <summary>Runs a finite source (an image sequence, a recording) to
        /// its end and yields every sheet, in order, as it comes, for
        /// <c>await foreach</c>: attaches and starts the source, and after
        /// its last frame ends the strip (a flush), so the last sheet comes
        /// too; then detaches it. The source's own error (e.g. a file it
        /// cannot read) is thrown after the sheets before it. Cancelling
        /// stops the acquisition (the sheets finished so far are yielded)
        /// and throws <see cref="OperationCanceledException"/>.
        /// <code>
        /// await foreach (var sheet in gauge.RunAsync(FrameSource.ImageDirectory("recording")))
        ///     Console.WriteLine($"{sheet.Id}: {sheet.ShapeName}, {sheet.MaxIUnits:F1} I-Units");
        /// </code></summary>
        public async IAsyncEnumerable<Sheet> RunAsync(FrameSource source,
                                                      [EnumeratorCancellation] CancellationToken cancellation = default)
        {
            if (source == null)
                throw new ArgumentNullException(nameof(source));
            var channel = new SheetChannel();
            lock (sync)
                channels.Add(channel);
            UpdateCallback();
            Task? ending = null;
            try
            {
                Attach(source);
                Start();
                // flt_gauge_wait in short steps on a pool thread: the sheets
                // reach the channel through the callback meanwhile, and the
                // flush after the source's end delivers the last before it
                // returns; then the channel ends.
                ending = Task.Run(() =>
                {
                    try
                    {
                        while (true)
                        {
                            if (cancellation.IsCancellationRequested)
                            {
                                Stop();
                                Flush();
                                cancellation.ThrowIfCancellationRequested();
                            }
                            int status = FlatlineNative.flt_cs_gauge_wait(LiveHandle, 50);
                            if (status != (int)Status.Timeout)
                            {
                                Errors.Check(status);
                                return;
                            }
                        }
                    }
                    finally
                    {
                        channel.Complete();
                    }
                });
                while (true)
                {
                    var sheet = await channel.ReadAsync(CancellationToken.None).ConfigureAwait(false);
                    if (sheet == null)
                        break;
                    yield return sheet;
                }
                await ending.ConfigureAwait(false);  // the source's error, or the cancellation
            }
            finally
            {
                if (ending != null && !ending.IsCompleted && !handle.IsClosed)
                {
                    // Left early: stop the acquisition (the wait then ends).
                    try
                    {
                        Stop();
                        ending.Wait();  // its wait now returns at once
                    }
                    catch (Exception)
                    {
                        // why the source would have ended is moot now
                    }
                }
                lock (sync)
                    channels.Remove(channel);
                if (!handle.IsClosed)
                {
                    UpdateCallback();
                    Attach(null);
                }
            }
        }

        /// <summary>The sheets as they are finished, for <c>await foreach</c>;
        /// the enumeration ends when the token is cancelled or the gauge is
        /// disposed.</summary>
        public async IAsyncEnumerable<Sheet> SheetsAsync([EnumeratorCancellation] CancellationToken cancellation = default)
        {
            var channel = new SheetChannel();
            lock (sync)
                channels.Add(channel);
            UpdateCallback();
            try
            {
                while (true)
                {
                    Sheet? sheet;
                    try
                    {
                        sheet = await channel.ReadAsync(cancellation).ConfigureAwait(false);
                    }
                    catch (OperationCanceledException)
                    {
                        yield break;
                    }
                    if (sheet == null)
                        yield break;  // the gauge was disposed
                    yield return sheet;
                }
            }
            finally
            {
                lock (sync)
                    channels.Remove(channel);
                if (!handle.IsClosed)
                    UpdateCallback();
            }
        }

        /// <summary>The rule set sheets are judged by (<see cref="SetRules"/>), or null.</summary>
        public ToleranceRules? Rules { get; private set; }

        /// <summary>Judges every sheet from now on against <paramref name="rules"/>:
        /// the sheets' thickness (mm) and width (<see cref="SheetWidth.Nominal"/>
        /// or <see cref="SheetWidth.Measured"/>) choose each rule's band; both
        /// are required (a sheet no band covers is not judged, never passed).
        /// The gauge keeps its own copy. The current coil's statistics restart;
        /// set the rules before a coil's first frame.</summary>
        public void SetRules(ToleranceRules rules, double thicknessMm, SheetWidth width)
        {
            if (rules == null)
                throw new ArgumentNullException(nameof(rules), "ClearRules() judges no more");
            FlatlineNative.flt_gauge_set_rules(LiveHandle, rules.LiveHandle, thicknessMm, width.Mm);
            Rules = rules;
        }

        /// <summary>Judges no more sheets (the current coil's statistics end).</summary>
        public void ClearRules()
        {
            FlatlineNative.flt_cs_gauge_clear_rules(LiveHandle);
            Rules = null;
        }

        /// <summary>The verdict statistics of the coil being measured; null
        /// without rules.</summary>
        public CoilStats? CurrentCoilStatistics() => CoilStatistics((int)NativeCoil.FLT_COIL_CURRENT);

        /// <summary>The verdict statistics of the last finished coil; null
        /// when none finished under rules yet.</summary>
        public CoilStats? LastCoilStatistics() => CoilStatistics((int)NativeCoil.FLT_COIL_LAST);

        private unsafe CoilStats? CoilStatistics(int coil)
        {
            int which = coil;
            int n = (int)NativeCoilValue.FLT_COIL_VALUES;
            double[] Read(int rule)
            {
                var v = new double[n];
                fixed (double* pv = v)
                    FlatlineNative.flt_cs_gauge_coil_stats(LiveHandle, which, (ulong)rule, (ulong)n, pv);
                return v;
            }
            double[] first;
            try
            {
                first = Read(0);
            }
            catch (FlatlineStateException)
            {
                return null;
            }
            var rules = new List<RuleStats> { new RuleStats(0, first) };
            for (int i = 1; i < (int)first[(int)NativeCoilValue.FLT_COIL_RULES]; ++i)
                rules.Add(new RuleStats(i, Read(i)));
            return new CoilStats(first, rules.AsReadOnly());
        }

        /// <summary>One of the gauge's counters.</summary>
        public unsafe ulong Count(GaugeCounter counter)
        {
            ulong value;
            FlatlineNative.flt_gauge_count(LiveHandle, (int)counter, &value);
            return value;
        }

        /// <summary>Every counter, by name.</summary>
        public IReadOnlyDictionary<GaugeCounter, ulong> Counters
        {
            get
            {
                var all = new Dictionary<GaugeCounter, ulong>();
                foreach (GaugeCounter c in Enum.GetValues(typeof(GaugeCounter)))
                    all[c] = Count(c);
                return all;
            }
        }

        /// <summary>Stops the acquisition and the workers and frees everything
        /// now (unfinished sheets are dropped; enumerations end). Further calls
        /// throw <see cref="ObjectDisposedException"/>; a second Dispose does
        /// nothing.</summary>
        public void Dispose()
        {
            handle.Dispose();
            lock (push)
            {
                attached?.DangerousRelease();
                attached = null;
                attachedRecorder?.DangerousRelease();
                attachedRecorder = null;
                attachedArchive?.DangerousRelease();
                attachedArchive = null;
            }
            SheetChannel[] open;
            lock (sync)
                open = channels.ToArray();
            foreach (var c in open)
                c.Complete();
            GC.SuppressFinalize(this);
        }

        private GaugeHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(Gauge));
                return handle;
            }
        }

        private void CheckFrame<T>(T[,] frame)
        {
            if (frame == null)
                throw new ArgumentNullException(nameof(frame));
            if (frame.GetLength(0) != FrameHeight || frame.GetLength(1) != FrameWidth)
                throw new ArgumentException(
                    $"the frame is [{frame.GetLength(0)}, {frame.GetLength(1)}], but the calibration's frames are " +
                    $"[{FrameHeight}, {FrameWidth}] (height, width)", nameof(frame));
        }

        // The native callback is set while a handler or an enumeration wants
        // the sheets; set outside `sync`, which the callback itself takes.
        private void UpdateCallback()
        {
            lock (registration)
            {
                bool want;
                lock (sync)
                    want = sheetFinished != null || channels.Count > 0;
                if (want == callbackSet || handle.IsClosed)
                    return;
                FlatlineNative.flt_gauge_set_callback(LiveHandle, want ? callbackPointer : IntPtr.Zero, IntPtr.Zero);
                callbackSet = want;
            }
        }

        // On a gauge thread (or the thread that set the callback, for the
        // sheets that were waiting): nothing may escape into native code.
        private void OnSheet(IntPtr nativeSheet, IntPtr user)
        {
            try
            {
                var sheet = Sheet.Read(nativeSheet, Maps);
                EventHandler<SheetEventArgs>? handlers;
                SheetChannel[] open;
                lock (sync)
                {
                    handlers = sheetFinished;
                    open = channels.ToArray();
                }
                foreach (var c in open)
                    c.Post(sheet);
                handlers?.Invoke(this, new SheetEventArgs(sheet));
            }
            catch (Exception e)
            {
                lock (sync)
                    handlerError ??= e;
            }
        }

        private void ThrowHandlerError()
        {
            Exception? e;
            lock (sync)
            {
                e = handlerError;
                handlerError = null;
            }
            if (e != null)
                throw new InvalidOperationException("a SheetFinished handler threw on the gauge's thread", e);
        }

        // An unbounded queue one enumeration reads.
        private sealed class SheetChannel
        {
            private readonly ConcurrentQueue<Sheet> sheets = new ConcurrentQueue<Sheet>();
            private readonly SemaphoreSlim available = new SemaphoreSlim(0);
            private volatile bool completed;

            public void Post(Sheet sheet)
            {
                sheets.Enqueue(sheet);
                available.Release();
            }

            public void Complete()
            {
                completed = true;
                available.Release();
            }

            public async Task<Sheet?> ReadAsync(CancellationToken cancellation)
            {
                while (true)
                {
                    if (sheets.TryDequeue(out Sheet? sheet))
                        return sheet;
                    if (completed)
                        return null;
                    await available.WaitAsync(cancellation).ConfigureAwait(false);
                }
            }
        }
    }
}
