// SPDX-License-Identifier: Apache-2.0
#nullable enable
using System;
using System.Text;

namespace Flatline
{
    /// <summary>One actuator of a leveler: its setting lies in [Min, Max] and
    /// moves by at most Step per advice (in its own Unit).</summary>
    public sealed class Actuator
    {
        internal Actuator(string name, string unit, double min, double max, double step)
        {
            Name = name;
            Unit = unit;
            Min = min;
            Max = max;
            Step = step;
        }

        public string Name { get; }
        public string Unit { get; }
        public double Min { get; }
        public double Max { get; }
        public double Step { get; }
        public override string ToString() =>
            FormattableString.Invariant($"{Name} [{Min}, {Max}] {Unit}, step {Step}");
    }

    /// <summary>The quality of an advisor's model: R² and RMS residual
    /// (I-Units) of the last identification over its steps; 1, 0, 0 for a G
    /// given by the vendor; NaN before any G or after a refusal for too few or
    /// degenerate steps.</summary>
    public sealed class AdvisorFit
    {
        internal AdvisorFit(double rSquared, double rmsIUnits, int steps)
        {
            RSquared = rSquared;
            RmsIUnits = rmsIUnits;
            Steps = steps;
        }

        public double RSquared { get; }
        public double RmsIUnits { get; }
        public int Steps { get; }
    }

    /// <summary>An advice: the change of every actuator's setting, the zone
    /// profile expected with it (I-Units) and the confidence in [0, 1].</summary>
    public sealed class Advice
    {
        internal Advice(double[] delta, double[] predicted, double confidence)
        {
            Delta = delta;
            Predicted = predicted;
            Confidence = confidence;
        }

        public double[] Delta { get; }
        public double[] Predicted { get; }
        public double Confidence { get; }
    }

    /// <summary>
    /// The leveler advisor (flatline/advisor.h): the leveler's actuators and
    /// its influence matrix G (zone I-Units per actuator unit), from the
    /// vendor's file (<see cref="Load"/>), an array, or identified from logged
    /// steps (<see cref="Identify"/>); <see cref="Advise"/> proposes the change
    /// of the settings after a sheet within every actuator's range and step
    /// limit. Not for two threads at once.
    /// </summary>
    public sealed class Advisor : IDisposable
    {
        /// <summary>The smallest R² of an accepted identification.</summary>
        public const double MinRSquared = FlatlineNative.FLT_ADVISOR_MIN_R_SQUARED;

        private readonly AdvisorHandle handle;

        static Advisor() => NativeLoader.EnsureLoaded();

        /// <summary>An advisor of <paramref name="zones"/> zones and
        /// <paramref name="actuators"/> actuators, G = 0: describe the actuators
        /// and set or identify G before advising. Options: AdvisorDamping,
        /// AdvisorGain (null: the defaults).</summary>
        public Advisor(int zones, int actuators, FlatlineOptions? options = null)
        {
            if (zones < 1)
                throw new ArgumentOutOfRangeException(nameof(zones), zones, "must be at least 1");
            if (actuators < 1)
                throw new ArgumentOutOfRangeException(nameof(actuators), actuators, "must be at least 1");
            AdvisorHandle created;
            using (var scope = FlatlineOptions.Borrow(options!))
            {
                FlatlineNative.flt_advisor_create((ulong)zones, (ulong)actuators, scope.Handle, out created);
            }
            handle = created;
            handle.Track(0);
            (Zones, Actuators) = ReadSize(handle);
        }

        private Advisor(AdvisorHandle loaded)
        {
            handle = loaded;
            handle.Track(0);
            (Zones, Actuators) = ReadSize(handle);
        }

        private static (int, int) ReadSize(AdvisorHandle h)
        {
            FlatlineNative.flt_advisor_size(h, out UIntPtr zones, out UIntPtr actuators);
            return ((int)zones.ToUInt64(), (int)actuators.ToUInt64());
        }

        /// <summary>Reads a leveler file ("flatline-leveler" version 1). A
        /// malformed one throws a FlatlineFormatException naming the field and
        /// its line.</summary>
        public static Advisor Load(string path, FlatlineOptions? options = null)
        {
            if (path == null)
                throw new ArgumentNullException(nameof(path));
            NativeLoader.EnsureLoaded();
            AdvisorHandle loaded;
            using (var scope = FlatlineOptions.Borrow(options!))
            {
                FlatlineNative.flt_advisor_load(path, scope.Handle, out loaded);
            }
            return new Advisor(loaded);
        }

        /// <summary>The same as <see cref="Load"/> from the file's text.</summary>
        public static Advisor Parse(string text, FlatlineOptions? options = null)
        {
            if (text == null)
                throw new ArgumentNullException(nameof(text));
            NativeLoader.EnsureLoaded();
            AdvisorHandle parsed;
            using (var scope = FlatlineOptions.Borrow(options!))
            {
                FlatlineNative.flt_advisor_load_text(text, (ulong)Encoding.UTF8.GetByteCount(text),
                                                     scope.Handle, out parsed);
            }
            return new Advisor(parsed);
        }

        /// <summary>The zone profile's length.</summary>
        public int Zones { get; }

        /// <summary>The number of actuators.</summary>
        public int Actuators { get; }

        /// <summary>Describes actuator <paramref name="index"/>: its name (1..63
        /// bytes of UTF-8), unit, range [min, max] and step limit (&gt; 0).</summary>
        public void SetActuator(int index, string name, string unit, double min, double max, double step)
        {
            if (index < 0)
                throw new ArgumentOutOfRangeException(nameof(index), index, "must not be negative");
            FlatlineNative.flt_advisor_set_actuator(LiveHandle, (ulong)index, name ?? throw new ArgumentNullException(nameof(name)),
                                                    unit ?? throw new ArgumentNullException(nameof(unit)), min, max, step);
        }

        /// <summary>Actuator <paramref name="index"/> as described (name "" and
        /// NaNs before).</summary>
        public Actuator GetActuator(int index)
        {
            if (index < 0)
                throw new ArgumentOutOfRangeException(nameof(index), index, "must not be negative");
            FlatlineNative.flt_advisor_actuator(LiveHandle, (ulong)index, out IntPtr name, out IntPtr unit,
                                                out double min, out double max, out double step);
            return new Actuator(Utf8.Decode(name), Utf8.Decode(unit), min, max, step);
        }

        /// <summary>G, [zones, actuators], I-Units per unit (a copy).</summary>
        public unsafe double[,] GetInfluence()
        {
            var g = new double[Zones, Actuators];
            fixed (double* p = g)
            {
                FlatlineNative.flt_advisor_influence(LiveHandle, p, (ulong)g.Length);
            }
            return g;
        }

        /// <summary>Sets G, [zones, actuators] (a vendor's matrix; its quality counts as 1).</summary>
        public unsafe void SetInfluence(double[,] g)
        {
            if (g == null)
                throw new ArgumentNullException(nameof(g));
            if (g.GetLength(0) != Zones || g.GetLength(1) != Actuators)
                throw new ArgumentException(
                    $"g is [{g.GetLength(0)}, {g.GetLength(1)}], the advisor has [{Zones}, {Actuators}]", nameof(g));
            fixed (double* p = g)
            {
                FlatlineNative.flt_advisor_set_influence(LiveHandle, p, (ulong)g.Length);
            }
        }

        /// <summary>The zone profile to aim at, I-Units [zones]; null: flat.</summary>
        public unsafe void SetTarget(double[]? target)
        {
            fixed (double* p = target)
            {
                FlatlineNative.flt_advisor_set_target(LiveHandle, p, (ulong)(target?.Length ?? 0));
            }
        }

        /// <summary>
        /// Identifies G from logged steps: deltaU [steps, actuators] the setting
        /// changes, deltaP [steps, zones] the profile changes they caused. A
        /// refused identification (too few or degenerate steps, R² below
        /// <see cref="MinRSquared"/>) throws a NumericException, and
        /// <see cref="Advise"/> then throws a FlatlineStateException.
        /// </summary>
        public unsafe AdvisorFit Identify(double[,] deltaU, double[,] deltaP, double ridge = 0)
        {
            if (deltaU == null)
                throw new ArgumentNullException(nameof(deltaU));
            if (deltaP == null)
                throw new ArgumentNullException(nameof(deltaP));
            if (deltaP.GetLength(0) != deltaU.GetLength(0))
                throw new ArgumentException(
                    $"deltaP has {deltaP.GetLength(0)} steps, deltaU {deltaU.GetLength(0)}", nameof(deltaP));
            fixed (double* du = deltaU)
            fixed (double* dp = deltaP)
            {
                FlatlineNative.flt_advisor_identify(LiveHandle, (ulong)deltaU.GetLength(0), du, (ulong)deltaU.Length,
                                                    dp, (ulong)deltaP.Length, ridge);
            }
            return Fit;
        }

        /// <summary>The quality of the model (see <see cref="AdvisorFit"/>).</summary>
        public AdvisorFit Fit
        {
            get
            {
                FlatlineNative.flt_advisor_fit(LiveHandle, out double r2, out double rms, out UIntPtr steps);
                return new AdvisorFit(r2, rms, (int)steps.ToUInt64());
            }
        }

        /// <summary>
        /// The change of the settings for a sheet's measured zone profile
        /// [zones], the settings that sheet went through [actuators] and the
        /// settings now [actuators] (null: the sheet's). Throws a
        /// FlatlineStateException when an actuator is not described, no G is
        /// set or the last identification was refused.
        /// </summary>
        public unsafe Advice Advise(double[] profile, double[] settingsSheet, double[]? settingsNow = null)
        {
            if (profile == null)
                throw new ArgumentNullException(nameof(profile));
            if (settingsSheet == null)
                throw new ArgumentNullException(nameof(settingsSheet));
            double[] now = settingsNow ?? settingsSheet;
            var delta = new double[Actuators];
            var predicted = new double[Zones];
            double confidence;
            fixed (double* p = profile)
            fixed (double* us = settingsSheet)
            fixed (double* un = now)
            fixed (double* d = delta)
            fixed (double* pr = predicted)
            {
                FlatlineNative.flt_advisor_advise(LiveHandle, p, (ulong)profile.Length, us,
                                                  (ulong)settingsSheet.Length, un, (ulong)now.Length, d,
                                                  (ulong)delta.Length, pr, (ulong)predicted.Length,
                                                  out confidence);
            }
            return new Advice(delta, predicted, confidence);
        }

        private AdvisorHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(Advisor));
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
