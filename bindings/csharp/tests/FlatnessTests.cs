// SPDX-License-Identifier: Apache-2.0
using System;
using System.Runtime.CompilerServices;
using System.Runtime.InteropServices;
using System.Threading;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>libflatline's flatness API called directly (see AgreementTests.cs).</summary>
    internal static unsafe partial class CReference
    {
        [DllImport(Core)] private static extern int flt_flatness_create(UIntPtr fibers, double* x, IntPtr options,
                                                                         out IntPtr flatness);
        [DllImport(Core)] private static extern void flt_flatness_destroy(IntPtr flatness);
        [DllImport(Core)] private static extern int flt_flatness_zones(IntPtr flatness, out UIntPtr zones);
        [DllImport(Core)] private static extern int flt_flatness_evaluate(IntPtr flatness, UIntPtr rows,
            UIntPtr fibers, double* s, double* z, byte* flags);
        [DllImport(Core)] private static extern int flt_flatness_push(IntPtr flatness, UIntPtr rows, UIntPtr fibers,
            double* s, double* z, byte* flags, out UIntPtr consumed, out int evaluated);
        [DllImport(Core)] private static extern int flt_flatness_fiber_results(IntPtr flatness, UIntPtr fibers,
            double* arc, double* iUnits, double* height, double* period, double* steepness, byte* flags);
        [DllImport(Core)] private static extern int flt_flatness_zone_results(IntPtr flatness, UIntPtr zones,
            double* iUnits, byte* flags);
        [DllImport(Core)] private static extern int flt_flatness_shape(IntPtr flatness, out int shape,
            out double confidence, out uint components, out double bow, out double crossbow);

        /// <summary>Every result of a window, flat: [fibers] x 5 doubles and
        /// flags, [zones] I-Units and flags, and the shape's 5 values.</summary>
        public sealed class FlatnessWindow
        {
            public required double[] Fiber;   // [5 * fibers]: arc, I, height, period, steepness
            public required byte[] FiberFlags;
            public required double[] Zone;
            public required byte[] ZoneFlags;
            public int Shape;
            public double Confidence, Bow, Crossbow;
            public uint Components;
        }

        private static FlatnessWindow Read(IntPtr flatness, int fibers)
        {
            Ok(flt_flatness_zones(flatness, out UIntPtr zones));
            int n = (int)zones;
            var w = new FlatnessWindow
            {
                Fiber = new double[5 * fibers], FiberFlags = new byte[fibers], Zone = new double[n],
                ZoneFlags = new byte[n],
            };
            fixed (double* pf = w.Fiber, pz = w.Zone)
            fixed (byte* ff = w.FiberFlags, zf = w.ZoneFlags)
            {
                Ok(flt_flatness_fiber_results(flatness, (UIntPtr)fibers, pf, pf + fibers, pf + 2 * fibers,
                                              pf + 3 * fibers, pf + 4 * fibers, ff));
                Ok(flt_flatness_zone_results(flatness, zones, pz, zf));
            }
            Ok(flt_flatness_shape(flatness, out w.Shape, out w.Confidence, out w.Components, out w.Bow,
                                  out w.Crossbow));
            return w;
        }

        /// <summary>Whole-sheet evaluation with default options; z and flags
        /// row-major [rows * fibers].</summary>
        public static FlatnessWindow FlatnessEvaluate(double[] x, double[] s, double[] z, byte[] flags)
        {
            IntPtr flatness;
            fixed (double* px = x)
                Ok(flt_flatness_create((UIntPtr)x.Length, px, IntPtr.Zero, out flatness));
            fixed (double* ps = s, pz = z)
            fixed (byte* pf = flags)
                Ok(flt_flatness_evaluate(flatness, (UIntPtr)s.Length, (UIntPtr)x.Length, ps, pz, pf));
            var w = Read(flatness, x.Length);
            flt_flatness_destroy(flatness);
            return w;
        }

        /// <summary>Streams the rows in one push after another, collecting
        /// every window evaluated (default options: 3000 mm every 1000 mm).</summary>
        public static System.Collections.Generic.List<FlatnessWindow> FlatnessStream(double[] x, double[] s,
                                                                                     double[] z, byte[] flags)
        {
            IntPtr flatness;
            fixed (double* px = x)
                Ok(flt_flatness_create((UIntPtr)x.Length, px, IntPtr.Zero, out flatness));
            var windows = new System.Collections.Generic.List<FlatnessWindow>();
            int fibers = x.Length;
            fixed (double* ps = s, pz = z)
            fixed (byte* pf = flags)
            {
                for (int first = 0; first < s.Length;)
                {
                    Ok(flt_flatness_push(flatness, (UIntPtr)(s.Length - first), (UIntPtr)fibers, ps + first,
                                         pz + first * fibers, pf + first * fibers, out UIntPtr consumed,
                                         out int evaluated));
                    first += (int)consumed;
                    if (evaluated != 0)
                        windows.Add(Read(flatness, fibers));
                }
            }
            flt_flatness_destroy(flatness);
            return windows;
        }
    }

    public class FlatnessTests
    {
        private readonly ITestOutputHelper output;
        public FlatnessTests(ITestOutputHelper output) => this.output = output;

        /// <summary>Rows every 3 mm over [0, length) of fibers whose heights
        /// are given by shape(x, s), mm.</summary>
        internal static (double[] s, double[,] z) Rows(double[] x, double lengthMm, Func<double, double, double> shape,
                                                       double s0 = 0.0)
        {
            int rows = (int)Math.Round(lengthMm / 3.0) + 1;
            var s = new double[rows];
            var z = new double[rows, x.Length];
            for (int r = 0; r < rows; ++r)
            {
                s[r] = s0 + 3.0 * r;
                for (int k = 0; k < x.Length; ++k)
                    z[r, k] = shape(x[k], s[r]);
            }
            return (s, z);
        }

        internal static double[] Grid(int fibers, double first, double pitch)
        {
            var x = new double[fibers];
            for (int k = 0; k < fibers; ++k)
                x[k] = first + pitch * k;
            return x;
        }

        /// <summary>A centre buckle (10 mm peak to peak over 1000 mm,
        /// cos^2 across 2000 mm) with reconstruction-like noise, some
        /// invalid samples flagged NoData and some bridged (InvalidInput).</summary>
        internal static (double[] x, double[] s, double[,] z, byte[,] flags) NoisySheet(double lengthMm, int seed)
        {
            double[] x = Grid(41, -1000, 50);
            var random = new Random(seed);
            var (s, z) = Rows(x, lengthMm, (xx, ss) =>
                5.0 * Math.Pow(Math.Cos(Math.PI * xx / 2000.0), 2) * Math.Sin(2 * Math.PI * ss / 1000.0));
            var flags = new byte[s.Length, x.Length];
            for (int r = 0; r < s.Length; ++r)
                for (int k = 0; k < x.Length; ++k)
                {
                    z[r, k] += 0.05 * (random.NextDouble() - 0.5);
                    double u = random.NextDouble();
                    if (u < 0.02)
                    {
                        flags[r, k] = (byte)ReconFlags.NoData;
                        z[r, k] = double.NaN;
                    }
                    else if (u < 0.05)
                        flags[r, k] = (byte)ReconFlags.InvalidInput;
                }
            // Fiber 3 has no data at all: it must be flagged, not crash.
            for (int r = 0; r < s.Length; ++r)
            {
                flags[r, 3] = (byte)ReconFlags.NoData;
                z[r, 3] = double.NaN;
            }
            return (x, s, z, flags);
        }

        [Fact]
        public void SineIUnitsAreTheAnalyticValuesWithinOnePercent()
        {
            // Fiber k: z = (H_k / 2) sin(2 pi s / P), P = 1000 mm, over three
            // whole periods; fiber 0 is flat, the I-Unit reference. For small
            // H/P, I = pi^2/4 (H/P)^2 1e5 (flatness.h); the next term is a
            // relative 3/16 (pi H/P)^2 < 0.1% here, and 3 mm chords of a
            // 1000 mm sine lose < 1e-5 relative: 1% is a wide margin that
            // still catches a wrong factor or a wrong reference.
            double[] heights = { 0, 5, 10, 15, 20 };
            double[] x = Grid(5, -200, 100);
            const double P = 1000.0;
            var (s, z) = Rows(x, 3000.0, (xx, ss) => 0.5 * heights[(int)Math.Round((xx + 200) / 100)] *
                                                      Math.Sin(2 * Math.PI * ss / P));
            using var options = new FlatlineOptions { FlatZoneWidth = 100 };
            using var flatness = new Flatness(x, options);
            Assert.Equal(5, flatness.Fibers);
            Assert.Equal(5, flatness.Zones);
            Assert.Equal(new[] { 1, 1, 1, 1, 1 }, flatness.ZoneFiberCount);
            var result = flatness.Evaluate(s, z);
            Assert.Equal(0.0, result.Fibers.IUnits[0]);
            Assert.Equal(3000.0, result.Fibers.ArcLength[0], 9);
            Assert.Equal(FiberFlags.NoWave, result.Fibers.Flags[0]);
            Assert.True(double.IsNaN(result.Fibers.WaveHeight[0]));
            for (int k = 1; k < heights.Length; ++k)
            {
                double expected = Math.PI * Math.PI / 4 * Math.Pow(heights[k] / P, 2) * 1e5;
                double got = result.Fibers.IUnits[k];
                output.WriteLine($"H {heights[k]} mm: I {got:F4} (analytic {expected:F4}, " +
                                 $"{100 * (got / expected - 1):+0.000;-0.000}%), wave {result.Fibers.WaveHeight[k]:F3} mm " +
                                 $"over {result.Fibers.WavePeriod[k]:F1} mm");
                Assert.InRange(got, 0.99 * expected, 1.01 * expected);
                Assert.InRange(result.Fibers.WaveHeight[k], 0.99 * heights[k], 1.01 * heights[k]);
                Assert.InRange(result.Fibers.WavePeriod[k], 0.99 * P, 1.01 * P);
                Assert.Equal(100 * result.Fibers.WaveHeight[k] / result.Fibers.WavePeriod[k],
                             result.Fibers.SteepnessPercent[k], 9);
                Assert.Equal(FiberFlags.None, result.Fibers.Flags[k]);
                // One fiber per zone: the zone profile is the fibers'.
                Assert.Equal(got, result.Zones.IUnits[k]);
            }
            Assert.Equal(0.0, result.Window.SFirstMm);
            Assert.Equal(3000.0, result.Window.SLastMm);
            Assert.Equal(s.Length, result.Window.Rows);
            Assert.Equal(1, result.Window.Index);
            Assert.Equal(Flatness.ShapeName(result.Shape.Class), result.Shape.Name);
            Assert.InRange(result.Shape.Confidence, 0.0, 1.0);
        }

        [Fact]
        public void ACentreBuckleWithBowAndCrossbowIsClassifiedAndMeasured()
        {
            // Centre buckle of 10 mm peak to peak, plus coil set of 3 mm
            // sagitta over the 3000 mm window (kappa = 8 * 3 / L^2) and a
            // crossbow of 4 mm from the centre to x = +-1000 mm.
            double[] x = Grid(41, -1000, 50);
            const double L = 3000.0, Bow = 3.0;
            double kappa = 8 * Bow / (L * L);
            var (s, z) = Rows(x, L, (xx, ss) =>
                5.0 * Math.Pow(Math.Cos(Math.PI * xx / 2000.0), 2) * Math.Sin(2 * Math.PI * ss / 1000.0) +
                0.5 * kappa * (ss - L / 2) * (ss - L / 2) + 4.0 * (xx / 1000.0) * (xx / 1000.0));
            using var flatness = new Flatness(x);
            var result = flatness.Evaluate(s, z);
            var shape = result.Shape;
            output.WriteLine($"{shape}, bow {shape.BowMm:F4} mm, crossbow {shape.CrossbowMm:F4} mm, " +
                             $"components {shape.Components}, centre zone {result.Zones.IUnits[result.Zones.Count / 2]:F2} I");
            Assert.Equal(ShapeClass.CentreBuckle, shape.Class);
            Assert.Equal("centre buckle", shape.Name);
            // Peak I = pi^2/4 (10/1000)^2 1e5 = 24.7, more than twice the
            // 5 I-Unit flat limit: the amplitude margin is 1, so the
            // confidence is the long material's share in the centre band.
            Assert.InRange(shape.Confidence, 0.5, 1.0);
            Assert.True(shape.Components.HasFlag(ShapeComponents.Centre));
            Assert.True(shape.Components.HasFlag(ShapeComponents.Bow));
            Assert.True(shape.Components.HasFlag(ShapeComponents.Crossbow));
            // The edge fibers (flattest quarter) carry the coil set alone:
            // the parabola fit gives it to rounding; 1% covers the buckle's
            // leak into the fibers next to the edges.
            Assert.InRange(shape.BowMm, 0.99 * Bow, 1.01 * Bow);
            // Crossbow: the sagitta over the width (about 2050 mm, fiber
            // pitch included) of 4 mm at +-1000 mm: 4 .. 4.3 mm.
            Assert.InRange(shape.CrossbowMm, 3.9, 4.4);
            Assert.Equal(WindowFlags.None, result.Window.Flags);
        }

        [Fact]
        public void EvaluateEqualsTheCLibraryBitwise()
        {
            var (x, s, z, flags) = NoisySheet(6000.0, 7);
            var c = CReference.FlatnessEvaluate(x, s, Flat(z), Flat(flags));
            using var flatness = new Flatness(x);
            var result = flatness.Evaluate(s, z, flags);
            int differences = CompareBitwise(c, result);
            output.WriteLine($"whole sheet: {x.Length * 6 + result.Zones.Count + 4} values compared, " +
                             $"{differences} differ bitwise; shape {result.Shape}");
            Assert.Equal(0, differences);
            // Not vacuous: the empty fiber is flagged, the others measured.
            Assert.Equal(FiberFlags.NoData, result.Fibers.Flags[3] & FiberFlags.NoData);
            Assert.True(result.Fibers.IUnits[20] > 10, $"centre fiber {result.Fibers.IUnits[20]} I");
        }

        [Fact]
        public void StreamedWindowsEqualTheCLibraryBitwise()
        {
            var (x, s, z, flags) = NoisySheet(10000.0, 8);
            var c = CReference.FlatnessStream(x, s, Flat(z), Flat(flags));
            using var flatness = new Flatness(x);
            int windows = 0, differences = 0;
            for (int first = 0; first < s.Length;)
            {
                var push = flatness.Push(s, z, flags, first);
                first += push.Consumed;
                if (!push.Evaluated)
                    continue;
                var result = flatness.Result();
                Assert.Equal(windows + 1, result.Window.Index);
                differences += CompareBitwise(c[windows], result);
                ++windows;
            }
            // Rows up to s = 9999 mm: windows end at 3000, 4000, .., 9000 mm.
            output.WriteLine($"{windows} streamed windows, {differences} values differ bitwise");
            Assert.Equal(7, windows);
            Assert.Equal(c.Count, windows);
            Assert.Equal(0, differences);
            // Finish evaluates the rest as the sheet's last window, from the
            // last window's start (7000 mm) to the last row: its first row
            // is the first at or past 7000 mm on the 3 mm grid, 7002 mm.
            Assert.True(flatness.Finish());
            var last = flatness.Result();
            Assert.Equal(7002.0, last.Window.SFirstMm);
            Assert.Equal(9999.0, last.Window.SLastMm);
            Assert.Equal(8, last.Window.Index);
            Assert.False(flatness.Finish());  // nothing pending
        }

        private static int CompareBitwise(CReference.FlatnessWindow c, FlatnessResult r)
        {
            int fibers = r.Fibers.Count, differences = 0;
            double[][] columns = { r.Fibers.ArcLength, r.Fibers.IUnits, r.Fibers.WaveHeight, r.Fibers.WavePeriod,
                                   r.Fibers.SteepnessPercent };
            for (int j = 0; j < 5; ++j)
                for (int k = 0; k < fibers; ++k)
                    differences += Same(c.Fiber[j * fibers + k], columns[j][k]) ? 0 : 1;
            for (int k = 0; k < fibers; ++k)
                differences += c.FiberFlags[k] == (byte)r.Fibers.Flags[k] ? 0 : 1;
            for (int j = 0; j < r.Zones.Count; ++j)
                differences += Same(c.Zone[j], r.Zones.IUnits[j]) && c.ZoneFlags[j] == (byte)r.Zones.Flags[j] ? 0 : 1;
            differences += c.Shape == (int)r.Shape.Class && c.Components == (uint)r.Shape.Components ? 0 : 1;
            differences += Same(c.Confidence, r.Shape.Confidence) && Same(c.Bow, r.Shape.BowMm) &&
                           Same(c.Crossbow, r.Shape.CrossbowMm) ? 0 : 1;
            return differences;
        }

        private static bool Same(double a, double b) =>
            BitConverter.DoubleToInt64Bits(a) == BitConverter.DoubleToInt64Bits(b);

        internal static T[] Flat<T>(T[,] a)
        {
            int rows = a.GetLength(0), cols = a.GetLength(1);
            var flat = new T[rows * cols];
            for (int r = 0; r < rows; ++r)
                for (int k = 0; k < cols; ++k)
                    flat[r * cols + k] = a[r, k];
            return flat;
        }

        [Fact]
        public void ErrorsMapToTheirExceptionsAndLeaveTheObjectUsable()
        {
            double[] x = Grid(5, 0, 100);
            using var flatness = new Flatness(x);
            Assert.Throws<FlatlineStateException>(() => flatness.Result());
            // Wrong shapes: ArgumentException before the native call.
            var (s, z) = Rows(x, 3000, (xx, ss) => Math.Sin(ss / 200.0));
            Assert.Throws<ArgumentException>(() => flatness.Evaluate(s, new double[s.Length, 4]));
            Assert.Throws<ArgumentException>(() => flatness.Evaluate(s, z, new byte[s.Length - 1, 5]));
            Assert.Throws<ArgumentNullException>(() => flatness.Evaluate(null!, z));  // null on purpose: the check under test
            Assert.Throws<ArgumentOutOfRangeException>(() => flatness.Push(s, z, null, s.Length + 1));
            // Values the C library rejects: its message names the argument.
            var e = Assert.Throws<InvalidArgumentException>(() => flatness.Evaluate(new[] { 0.0 }, new double[1, 5]));
            Assert.Equal(Status.InvalidArgument, e.Status);
            output.WriteLine(e.Message);
            var backwards = (double[])s.Clone();
            backwards[10] = backwards[9];
            Assert.Throws<InvalidArgumentException>(() => flatness.Evaluate(backwards, z));
            // 300 mm of strip is shorter than flat_min_length (500 mm).
            var (shortS, shortZ) = Rows(x, 300, (xx, ss) => 0.0);
            Assert.Throws<InvalidArgumentException>(() => flatness.Evaluate(shortS, shortZ));
            Assert.Throws<FlatlineStateException>(() => flatness.Result());  // still no window
            Assert.Throws<InvalidArgumentException>(() => new Flatness(new[] { 0.0, 0.0 }));
            Assert.Throws<InvalidArgumentException>(() => new Flatness(
                x, new FlatlineOptions { FlatWindowLength = 1000, FlatUpdateInterval = 2000 }));
            // A window bigger than the row capacity: BufferFull.
            using (var small = new Flatness(x, new FlatlineOptions { FlatWindowLength = 0, FlatRowCapacity = 16 }))
            {
                var full = Assert.Throws<BufferFullException>(() => small.Push(s, z));
                Assert.Equal(Status.BufferFull, full.Status);
                small.Reset();
                Assert.Equal(10, small.Push(s, z, null, 0, 10).Consumed);
            }
            // Usable after every error: a good sheet evaluates.
            var result = flatness.Evaluate(s, z);
            Assert.Equal(1, result.Window.Index);
            Assert.Equal(s.Length, result.Window.Rows);
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static Flatness FlatnessOwningTheOnlyReference(out WeakReference calibration)
        {
            var calib = Calibration.Reference(firstRow: 960, rows: 128, firstXMm: -800, pitchMm: 20, fibers: 81);
            calibration = new WeakReference(calib);
            return new Flatness(calib);
        }

        [Fact]
        public void FlatnessOfACalibrationKeepsItAliveAndUsesItsFiberGrid()
        {
            Flatness flatness = FlatnessOwningTheOnlyReference(out WeakReference calibration);
            for (int i = 0; i < 3; ++i)
            {
                GC.Collect();
                GC.WaitForPendingFinalizers();
            }
            Assert.True(calibration.IsAlive, "the calibration was collected while its flatness lives");
            Assert.Same(calibration.Target, flatness.Calibration);
            Assert.Equal(81, flatness.Fibers);
            // 81 fibers every 20 mm: width 1620 mm, 50 mm zones: ceil(32.4) = 33.
            Assert.Equal(33, flatness.Zones);
            Assert.Equal(81, Sum(flatness.ZoneFiberCount));  // every fiber in one zone
            var (s, z) = Rows(FlatnessTests.Grid(81, -800, 20), 3000, (xx, ss) => Math.Sin(ss / 300.0));
            Assert.Equal(81, flatness.Evaluate(s, z).Fibers.Count);
            flatness.Dispose();
        }

        private static int Sum(int[] values)
        {
            int sum = 0;
            foreach (int v in values)
                sum += v;
            return sum;
        }

        [Fact]
        public void DisposeIsImmediateIdempotentAndFinal()
        {
            Finalizers.Settle();
            long before = FlatnessHandle.Live;
            var flatness = new Flatness(Grid(5, 0, 100));
            Assert.Equal(before + 1, FlatnessHandle.Live);
            flatness.Dispose();
            Assert.Equal(before, FlatnessHandle.Live);
            flatness.Dispose();
            Assert.Throws<ObjectDisposedException>(() => flatness.Result());
            Assert.Throws<ObjectDisposedException>(() => flatness.Finish());
            Assert.Throws<ObjectDisposedException>(() => flatness.Reset());
            Assert.Throws<ObjectDisposedException>(() => flatness.Evaluate(new double[2], new double[2, 5]));
        }

        [Fact]
        public void TwoFlatnessObjectsOnTwoThreadsMatchSerialRunsBitwise()
        {
            var (x, s, z, flags) = NoisySheet(10000.0, 9);
            double[] Run()
            {
                using var flatness = new Flatness(x);
                var zones = new System.Collections.Generic.List<double>();
                for (int first = 0; first < s.Length;)
                {
                    var push = flatness.Push(s, z, flags, first);
                    first += push.Consumed;
                    if (push.Evaluated)
                        zones.AddRange(flatness.Result().Zones.IUnits);
                }
                Assert.True(flatness.Finish());
                zones.AddRange(flatness.Result().Fibers.IUnits);
                return zones.ToArray();
            }
            double[] serial = Run();
            double[]? a = null, b = null;
            Exception? failure = null;
            // A failed assertion on a thread is caught and rethrown here (an
            // exception escaping a thread would end the test process).
            ThreadStart Guarded(Action run) => () =>
            {
                try { run(); }
                catch (Exception e) { failure = e; }
            };
            var threadA = new Thread(Guarded(() => a = Run()));
            var threadB = new Thread(Guarded(() => b = Run()));
            threadA.Start();
            threadB.Start();
            threadA.Join();
            threadB.Join();
            if (failure != null)
                throw failure;
            Assert.NotNull(a);
            Assert.NotNull(b);
            Assert.Equal(serial.Length, a.Length);
            Assert.Equal(serial.Length, b.Length);
            for (int i = 0; i < serial.Length; ++i)
            {
                Assert.True(Same(serial[i], a[i]), $"thread A value {i}");
                Assert.True(Same(serial[i], b[i]), $"thread B value {i}");
            }
            output.WriteLine($"{serial.Length} zone and fiber I-Units equal bitwise on two threads");
        }
    }
}
