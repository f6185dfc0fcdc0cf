// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.Text;

namespace Flatline
{
    /// <summary>What a tolerance rule measures (flt_measure).</summary>
    public enum Measure
    {
        /// <summary>Straightedge deviation along every fiber, mm.</summary>
        StraightedgeAlong = NativeMeasure.FLT_MEASURE_STRAIGHTEDGE_ALONG,
        /// <summary>Straightedge deviation across every row, mm.</summary>
        StraightedgeAcross = NativeMeasure.FLT_MEASURE_STRAIGHTEDGE_ACROSS,
        /// <summary>The largest zone I-Units.</summary>
        ZoneIUnits = NativeMeasure.FLT_MEASURE_ZONE_I_UNITS,
        /// <summary>Wave steepness, %.</summary>
        WaveSteepness = NativeMeasure.FLT_MEASURE_WAVE_STEEPNESS,
        /// <summary>Wave height peak to peak, mm.</summary>
        WaveHeight = NativeMeasure.FLT_MEASURE_WAVE_HEIGHT,
        /// <summary>Bow, mm (its magnitude is judged).</summary>
        Bow = NativeMeasure.FLT_MEASURE_BOW,
        /// <summary>Crossbow, mm (its magnitude is judged).</summary>
        Crossbow = NativeMeasure.FLT_MEASURE_CROSSBOW,
    }

    /// <summary>A rule's outcome on a sheet (flt_verdict_state).</summary>
    public enum VerdictState
    {
        /// <summary>The worst value is at most the limit.</summary>
        Pass = NativeVerdictState.FLT_VERDICT_PASS,
        /// <summary>The worst value exceeds the limit.</summary>
        Fail = NativeVerdictState.FLT_VERDICT_FAIL,
        /// <summary>No band of the rule covers the sheet's thickness and width.</summary>
        NoBand = NativeVerdictState.FLT_VERDICT_NO_BAND,
        /// <summary>No map (straightedges), or the value was not given.</summary>
        NotMeasured = NativeVerdictState.FLT_VERDICT_NOT_MEASURED,
        /// <summary>Not judged: the gauge's sheet is incomplete; also a whole
        /// sheet's verdict (<see cref="Sheet.VerdictState"/>) when a rule could
        /// not judge it. Never a pass.</summary>
        NotJudged = NativeVerdictState.FLT_VERDICT_NOT_JUDGED,
    }

    /// <summary>One rule of a rule set.</summary>
    public sealed class ToleranceRule
    {
        internal ToleranceRule(string name, Measure measure, double lengthMm)
        {
            Name = name;
            Measure = measure;
            LengthMm = lengthMm;
        }

        public string Name { get; }
        public Measure Measure { get; }
        /// <summary>The straightedge's length, mm; 0 for other measures.</summary>
        public double LengthMm { get; }
        public override string ToString() => $"{Name} ({Measure})";
    }

    /// <summary>One rule's verdict on a sheet. Worst, Margin, XMm and SMm
    /// are NaN unless the state is Pass or Fail; Limit is NaN with NoBand.</summary>
    public sealed class RuleResult
    {
        internal RuleResult(ToleranceRule rule, VerdictState state, double worst, double limit,
                            double margin, double xMm, double sMm, int band)
        {
            Rule = rule;
            State = state;
            Worst = worst;
            Limit = limit;
            Margin = margin;
            XMm = xMm;
            SMm = sMm;
            Band = band;
        }

        public ToleranceRule Rule { get; }
        public VerdictState State { get; }
        /// <summary>The worst value found (the measure's unit).</summary>
        public double Worst { get; }
        /// <summary>The limit of the band that applies.</summary>
        public double Limit { get; }
        /// <summary>Limit - Worst: at least 0 passes.</summary>
        public double Margin { get; }
        /// <summary>Where the worst value is: across the strip, mm.</summary>
        public double XMm { get; }
        /// <summary>... and along it, mm.</summary>
        public double SMm { get; }
        /// <summary>The band's index in the rule file; -1 with NoBand.</summary>
        public int Band { get; }
        public bool Passed => State == VerdictState.Pass;
        public override string ToString() => $"{Rule.Name}: {State} ({Worst} of {Limit})";
    }

    /// <summary>
    /// A rule set of flatness tolerances, read from a rule file (UTF-8 JSON,
    /// "flatline-tolerances" version 1; flatline/verdict.h, "Rule files").
    /// Read-only: threads may share it.
    /// </summary>
    public sealed class ToleranceRules : IDisposable
    {
        private readonly RulesHandle handle;

        static ToleranceRules() => NativeLoader.EnsureLoaded();

        private ToleranceRules(RulesHandle handle)
        {
            this.handle = handle;
            handle.Track(0);
            var list = new List<ToleranceRule>();
            FlatlineNative.flt_rules_count(handle, out UIntPtr count);
            unsafe
            {
                for (ulong i = 0; i < count.ToUInt64(); ++i)
                {
                    int measure;
                    double length;
                    FlatlineNative.flt_rules_rule(handle, i, out IntPtr name, &measure, &length);
                    list.Add(new ToleranceRule(Utf8.Decode(name), (Measure)measure, length));
                }
            }
            Rules = list.AsReadOnly();
        }

        /// <summary>Reads a rule file. A malformed one throws a FlatlineFormatException
        /// naming the field and its line.</summary>
        public static ToleranceRules Load(string path)
        {
            if (path == null)
                throw new ArgumentNullException(nameof(path));
            NativeLoader.EnsureLoaded();
            FlatlineNative.flt_rules_load(path, out RulesHandle loaded);
            return new ToleranceRules(loaded);
        }

        /// <summary>The same as <see cref="Load"/> from the file's text.</summary>
        public static ToleranceRules Parse(string text)
        {
            if (text == null)
                throw new ArgumentNullException(nameof(text));
            NativeLoader.EnsureLoaded();
            FlatlineNative.flt_rules_load_text(text, (ulong)Encoding.UTF8.GetByteCount(text),
                                               out RulesHandle parsed);
            return new ToleranceRules(parsed);
        }

        /// <summary>The rules, in file order.</summary>
        public IReadOnlyList<ToleranceRule> Rules { get; }

        internal RulesHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(ToleranceRules));
                return handle;
            }
        }

        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }
    }

    /// <summary>
    /// Judges sheets against a rule set (it keeps its own copy): give the
    /// flatness measures with <see cref="SetMeasure"/>, then
    /// <see cref="Evaluate"/> a sheet's height map. Not for two threads at once.
    /// </summary>
    public sealed class Verdict : IDisposable
    {
        private readonly VerdictHandle handle;
        private readonly IReadOnlyList<ToleranceRule> rules;

        static Verdict() => NativeLoader.EnsureLoaded();

        public Verdict(ToleranceRules rules)
        {
            if (rules == null)
                throw new ArgumentNullException(nameof(rules));
            this.rules = rules.Rules;
            FlatlineNative.flt_verdict_create(rules.LiveHandle, out VerdictHandle created);
            handle = created;
            handle.Track(0);
        }

        /// <summary>
        /// The straightedge deviation of one profile: the largest gap between
        /// it and a straightedge of <paramref name="lengthMm"/> resting on two
        /// contacts (flatline/verdict.h, "Measures"), and where its deepest
        /// point is. Positions strictly increasing (mm); NaN heights are left out.
        /// </summary>
        public static unsafe (double DeviationMm, double AtMm) Straightedge(
            double[] positionsMm, double[] heightsMm, double lengthMm)
        {
            if (positionsMm == null)
                throw new ArgumentNullException(nameof(positionsMm));
            if (heightsMm == null)
                throw new ArgumentNullException(nameof(heightsMm));
            if (heightsMm.Length != positionsMm.Length)
                throw new ArgumentException(
                    $"heightsMm has {heightsMm.Length} samples, positionsMm {positionsMm.Length}",
                    nameof(heightsMm));
            NativeLoader.EnsureLoaded();
            double deviation, at;
            fixed (double* p = positionsMm)
            fixed (double* z = heightsMm)
            {
                FlatlineNative.flt_straightedge_profile(p, z, (ulong)positionsMm.Length, lengthMm,
                                                        &deviation, &at);
            }
            return (deviation, at);
        }

        /// <summary>One of the flatness measures (not a straightedge) and where
        /// it is; it stays until given again. NaN: not measured.</summary>
        public void SetMeasure(Measure measure, double value, double xMm = 0, double sMm = 0) =>
            FlatlineNative.flt_verdict_set_measure(LiveHandle, (int)measure, value, xMm, sMm);

        /// <summary>
        /// Judges one sheet: its thickness and width (mm) choose each rule's
        /// band; s [rows], x [fibers] and z [rows, fibers] are its height map
        /// (mm, NaN = not measured; all null: no map, the straightedge rules
        /// are NotMeasured); flags [rows, fibers] its FLT_FLAG_* bits or null.
        /// </summary>
        public unsafe IReadOnlyList<RuleResult> Evaluate(double thicknessMm, double widthMm,
                                                         double[]? s = null, double[]? x = null,
                                                         double[,]? z = null, byte[,]? flags = null)
        {
            var live = LiveHandle;
            ulong rows = 0, fibers = 0;
            if (s != null || x != null || z != null)
            {
                if (s == null || x == null || z == null)
                    throw new ArgumentException("s, x and z come together (or none of them)");
                rows = (ulong)z.GetLength(0);
                fibers = (ulong)z.GetLength(1);
                if ((ulong)s.Length != rows)
                    throw new ArgumentException($"s has {s.Length} rows, z {rows}", nameof(s));
                if ((ulong)x.Length != fibers)
                    throw new ArgumentException($"x has {x.Length} fibers, z {fibers}", nameof(x));
                if (flags != null && ((ulong)flags.GetLength(0) != rows || (ulong)flags.GetLength(1) != fibers))
                    throw new ArgumentException("flags must have z's shape", nameof(flags));
            }
            fixed (double* ps = s)
            fixed (double* px = x)
            fixed (double* pz = z)
            fixed (byte* pf = flags)
            {
                FlatlineNative.flt_verdict_evaluate(live, thicknessMm, widthMm, rows, fibers, ps, px,
                                                    pz, pf);
            }
            return Results();
        }

        /// <summary>The results of the last evaluation, in rule order.</summary>
        public IReadOnlyList<RuleResult> Results()
        {
            var live = LiveHandle;
            var list = new List<RuleResult>(rules.Count);
            for (int i = 0; i < rules.Count; ++i)
            {
                double Get(NativeVerdictValue key)
                {
                    FlatlineNative.flt_verdict_get(live, (ulong)i, (int)key, out double v);
                    return v;
                }
                list.Add(new RuleResult(rules[i], (VerdictState)(int)Get(NativeVerdictValue.FLT_VERDICT_STATE),
                                        Get(NativeVerdictValue.FLT_VERDICT_WORST),
                                        Get(NativeVerdictValue.FLT_VERDICT_LIMIT),
                                        Get(NativeVerdictValue.FLT_VERDICT_MARGIN),
                                        Get(NativeVerdictValue.FLT_VERDICT_X),
                                        Get(NativeVerdictValue.FLT_VERDICT_S),
                                        (int)Get(NativeVerdictValue.FLT_VERDICT_BAND)));
            }
            return list.AsReadOnly();
        }

        /// <summary>The number of rules that failed in the last evaluation.</summary>
        public int Failed
        {
            get
            {
                FlatlineNative.flt_verdict_failed(LiveHandle, out UIntPtr n);
                return (int)n.ToUInt64();
            }
        }

        private VerdictHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(Verdict));
                return handle;
            }
        }

        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }
    }
}
