// SPDX-License-Identifier: Apache-2.0
using System;
using System.Runtime.CompilerServices;
using System.Threading;
using Xunit;

namespace Flatline.Tests
{
    public class SimulatedLineTests
    {
        private readonly ITestOutputHelper output;
        public SimulatedLineTests(ITestOutputHelper output) => this.output = output;

        /// <summary>Rows 960..1087 of the reference sensor: both lines and
        /// +-50 mm of height fit (0.48 px/mm), a frame is 1/16 of the full
        /// sensor's. 21 fibers every 100 mm.</summary>
        internal static Calibration SmallSensor() => Calibration.Reference(960, 128, -1000, 100, 21);

        /// <summary>The disturbances of a real line: rigid heave and roll,
        /// run-out, peak noise; seeded.</summary>
        private static FlatlineOptions Noisy(uint seed) => new FlatlineOptions
        {
            SimSeed = seed, SimHeaveSigma = 2.5, SimTiltSigma = 1e-3, SimEccentricityAmplitude = 0.2,
            SimPeakSigma = 0.0625, SimStart = 500,
        };

        private static readonly (string, double)[] NoisyByName =
        {
            ("sim_seed", 9), ("sim_heave_sigma", 2.5), ("sim_tilt_sigma", 1e-3),
            ("sim_eccentricity_amplitude", 0.2), ("sim_peak_sigma", 0.0625), ("sim_start", 500),
        };

        [Fact]
        public void TheDefaultLineIsTheWholeReferenceSensor()
        {
            using var line = new SimulatedLine();
            Assert.Equal(1001, line.Fibers);
            Assert.Equal(2048, line.FrameWidth);
            Assert.Equal(2048, line.FrameHeight);
            Assert.Equal(PixelFormat.Mono8, line.PixelFormat);
            Assert.True(line.Calibration.IsFinished);
            Assert.Equal(new FiberGrid(-1000, 2, 1001), line.Calibration.FiberGrid);
            using var calib = SmallSensor();
            using var options = new FlatlineOptions { SimBitDepth = 12 };
            using var small = new SimulatedLine(calib, options);
            Assert.Same(calib, small.Calibration);
            Assert.Equal(21, small.Fibers);
            Assert.Equal(128, small.FrameHeight);
            Assert.Equal(PixelFormat.Mono12, small.PixelFormat);
        }

        [Fact]
        public void DefectsAndHeightMapMakeTheSurface()
        {
            using var calib = SmallSensor();
            using var line = new SimulatedLine(calib);
            Assert.Equal(0.0, line.Surface(0, 450));  // starts flat
            line.AddDefect(DefectKind.CentreBuckle, 12, 1800);
            // g = cos^2(pi x / W) = 1 at the centre, sin = 1 at s = P/4 (sim.h).
            Assert.Equal(12.0, line.Surface(0, 450), 12);
            Assert.Equal(6.0, line.Surface(500, 450), 12);  // cos^2(pi/4) = 1/2 with W = 2000
            line.AddDefect(DefectKind.Bow, 2);               // period 0: constant
            Assert.Equal(2.0, line.Surface(-1000, 0), 12);
            double[] z = line.Surface(new[] { 0.0, 500.0 }, new[] { 450.0, 450.0 });
            Assert.Equal(14.0, z[0], 12);
            Assert.Equal(8.0, z[1], 12);
            line.ClearSheet();
            Assert.Equal(0.0, line.Surface(0, 450));
            // A 2 x 3 map, bilinear between its nodes: row r at s = 100 + 50 r, column c at x = -10 + 10 c.
            line.SetHeightMap(new double[,] { { 0, 1, 2 }, { 4, 5, 6 } }, 100, 50, -10, 10);
            Assert.Equal(2.5, line.Surface(-5, 125), 12);  // mean of 0, 1, 4, 5
            Assert.Equal(6.0, line.Surface(50, 500), 12);  // clamped to the corner
            Assert.Equal("s", Assert.Throws<ArgumentException>(() => line.Surface(new double[2], new double[3])).ParamName);
        }

        [Fact]
        public void NoiseFreeRowsAreTheTwoLaserOperatorsOfTheSurface()
        {
            using var calib = SmallSensor();
            using var options = new FlatlineOptions { SimStart = 1000, SimFrameSpacing = 3 };
            using var line = new SimulatedLine(calib, options);
            line.AddDefect(DefectKind.CentreBuckle, 12, 1800);
            line.AddDefect(DefectKind.WavyEdgeLeft, 5, 700);
            SimulatedRows rows = line.NextRows(200);
            Assert.Equal(200, rows.Rows);
            Assert.Equal(21, rows.Fibers);
            for (int r = 0; r < rows.Rows; ++r)
            {
                Assert.Equal(1000 + 3.0 * r, rows.EncoderMm[r], 9);
                Assert.Equal(rows.EncoderMm[r], rows.S[r], 9);  // offsets -50 and +50: s = e
                for (int k = 0; k < rows.Fibers; ++k)
                {
                    double x = calib.FiberGrid.X(k);
                    double ahead = line.Surface(x, rows.S[r] + 50), behind = line.Surface(x, rows.S[r] - 50);
                    // 1e-12 mm is rounding (the C test's tolerance).
                    Assert.True(Math.Abs(rows.Height[r, k] - (ahead + behind) / 2) < 1e-12);
                    Assert.True(Math.Abs(rows.Slope[r, k] - (ahead - behind) / 100) < 1e-14);
                    Assert.True(Math.Abs(rows.Truth[r, k] - line.Surface(x, rows.S[r])) < 1e-12);
                    Assert.True(rows.Valid[r, k]);
                }
            }
            // The next block continues the frame counter.
            Assert.Equal(1000 + 3.0 * 200, line.NextRows(1).EncoderMm[0], 9);
        }

        [Fact]
        public void NoiseFreeRowsReconstructWithinAMicronOfTheTruth()
        {
            using var calib = SmallSensor();
            using var options = new FlatlineOptions { SimFrameSpacing = 3 };
            using var line = new SimulatedLine(calib, options);
            line.AddDefect(DefectKind.CentreBuckle, 12, 1800);
            line.AddDefect(DefectKind.QuarterBuckle, 4, 2400);
            SimulatedRows rows = line.NextRows(2000);  // 6 m of strip
            ReconResult result = Library.Reconstruct(rows.S, rows.Height, rows.Slope, rows.Valid);
            double error = Sheet.MaxError(result.Z, rows.Truth);
            output.WriteLine($"simulated rows -> batch reconstruction: max error {error:E2} mm");
            // Cubic Hermite interpolation at 100 mm knots: h^4/384 max|z''''|
            // = 4.6e-4 mm for the 12 mm, 1800 mm buckle, less for the 2400 mm one.
            Assert.True(error < 1e-3, $"max error {error} mm");
            using var recon = new Reconstructor(rows.Fibers);
            var streamed = Sheet.Stream(recon, new Sheet { S = rows.S, Height = rows.Height, Slope = rows.Slope }, 50);
            double streamedError = Sheet.MaxError(streamed.Z, rows.Truth);
            output.WriteLine($"simulated rows -> streaming reconstruction: max error {streamedError:E2} mm");
            Assert.True(streamedError < 1e-3, $"max error {streamedError} mm");
        }

        [Fact]
        public void FramesDrawTheLinesWhereTheCalibrationSays()
        {
            using var calib = SmallSensor();
            using var options = new FlatlineOptions { SimSpeckle = 0, SimFullWell = 0, SimStart = 321 };
            using var line = new SimulatedLine(calib, options);
            line.AddDefect(DefectKind.CentreBuckle, 12, 1800);
            SimulatedFrame frame = line.NextFrame();
            Assert.Equal(PixelFormat.Mono8, frame.Format);
            Assert.Null(frame.Pixels16);
            Assert.Same(frame.Pixels8, frame.Pixels);
            Assert.Equal(2048, frame.Width);
            Assert.Equal(128, frame.Height);
            Assert.Equal(321.0, frame.EncoderMm, 12);
            Assert.Equal(21, frame.Truth.Length);
            Assert.Equal(line.Surface(0, 321), frame.Truth[10], 12);
            int checkedPixels = 0;
            for (int laser = 0; laser < 2; ++laser)
                for (int u = 2; u < 2046; u += 31)
                {
                    double v = frame.PeakRows[laser, u];
                    Assert.False(double.IsNaN(v));
                    // The line centre maps back onto the surface at the laser's s (2 um).
                    double[,] plane = calib.ImageToPlane(laser, new double[,] { { u, v } });
                    double s = frame.EncoderMm - calib.GetLaserOffset(laser);
                    Assert.True(Math.Abs(plane[0, 1] - line.Surface(plane[0, 0], s)) < 2e-3);
                    // Background 3 % + a Gaussian line of sigma 2 px, 60 % of full scale (sim.h defaults).
                    int row = (int)Math.Round(v);
                    double d = row - v;
                    double expected = 0.03 * 255 + 0.6 * 255 * Math.Exp(-d * d / 8);
                    Assert.True(Math.Abs(frame.Mono8()[row, u] - expected) <= 0.5 + 1e-9);
                    ++checkedPixels;
                }
            Assert.Equal(2 * 66, checkedPixels);
        }

        [Fact]
        public void SixteenBitFramesComeAsUshortsInTheirBitDepth()
        {
            using var calib = SmallSensor();
            // A line peak of twice full scale saturates the line centres.
            using var options = new FlatlineOptions { SimBitDepth = 12, SimLinePeak = 2.0 };
            using var line = new SimulatedLine(calib, options);
            SimulatedFrame frame = line.NextFrame();
            Assert.Equal(PixelFormat.Mono12, frame.Format);
            Assert.Null(frame.Pixels8);
            ushort max = 0;
            foreach (ushort p in frame.Mono16())
                max = Math.Max(max, p);
            Assert.Equal(4095, max);  // full scale of 12 bits, never more
            // Row 0 (sensor row 960) is 36 px from the nearest line: background,
            // 3 % of 4095 = 122.85, with shot noise of sigma sqrt(122.85 x 4095 /
            // 10000) = 7.1 counts per pixel, 0.16 on the mean of 2048.
            double mean = 0;
            for (int u = 0; u < 2048; ++u)
                mean += frame.Mono16()[0, u] / 2048.0;
            output.WriteLine($"Mono12 background mean {mean:F2} counts (expected 122.85)");
            Assert.InRange(mean, 121.85, 123.85);
            var pixels = new ushort[128, 2048];
            double e = line.NextFrame(pixels);
            Assert.Equal(3.0, e, 12);  // the second frame, 3 mm on
            Assert.Equal("pixels", Assert.Throws<ArgumentException>(() => line.NextFrame(new byte[128, 2048])).ParamName);
            Assert.Equal("pixels", Assert.Throws<ArgumentException>(() => line.NextFrame(new ushort[127, 2048])).ParamName);
            Assert.Equal("truth", Assert.Throws<ArgumentException>(() => line.NextFrame(pixels, new double[20])).ParamName);
            Assert.Equal("peakRows", Assert.Throws<ArgumentException>(() =>
                line.NextFrame(pixels, null, new double[2, 2047])).ParamName);
            // None of those rendered a frame: the next is the third.
            Assert.Equal(6.0, line.NextFrame().EncoderMm, 12);
        }

        [Fact]
        public void TheSameSeedGivesTheSameOutputAndRewindRepeatsIt()
        {
            using var calib = SmallSensor();
            using var o7 = Noisy(7);
            using var o8 = Noisy(8);
            using var a = new SimulatedLine(calib, o7);
            using var b = new SimulatedLine(calib, o7);
            using var c = new SimulatedLine(calib, o8);
            foreach (var line in new[] { a, b, c })
                line.AddDefect(DefectKind.WavyEdgeBoth, 6, 900);
            SimulatedRows ra = a.NextRows(300), rb = b.NextRows(300), rc = c.NextRows(300);
            Sheet.AssertBitwise(ra.Height, rb.Height);
            Sheet.AssertBitwise(ra.Slope, rb.Slope);
            Assert.Equal(ra.S, rb.S);
            Assert.NotEqual(ra.Height[5, 3], rc.Height[5, 3]);  // another seed, other noise
            Assert.Equal(ra.Truth[5, 3], rc.Truth[5, 3]);       // on the same sheet
            byte[,] fa = a.NextFrame().Mono8(), fb = b.NextFrame().Mono8();
            Assert.Equal(fa, fb);
            a.Rewind();
            SimulatedRows again = a.NextRows(300);
            Sheet.AssertBitwise(ra.Height, again.Height);
            Assert.Equal(fa, a.NextFrame().Pixels8);
        }

        [Fact]
        public void RowsAndFramesEqualTheCLibraryBitwise()
        {
            // An ROI calibration, and the C default (calib NULL) against new SimulatedLine().
            foreach (bool roi in new[] { true, false })
            {
                int blocks = 3, count = roi ? 100 : 20;
                var c = CReference.Simulate(roi, NoisyByName, blocks, count);
                using var calib = roi ? SmallSensor() : null;
                using var options = Noisy(9);
                using var line = new SimulatedLine(calib, options);
                line.AddDefect(DefectKind.CentreBuckle, 12, 1800);
                int fibers = line.Fibers, differences = 0;
                for (int b = 0; b < blocks; ++b)
                {
                    SimulatedRows rows = line.NextRows(count);
                    for (int r = 0; r < count; ++r)
                    {
                        int i = b * count + r;
                        differences += Bits(rows.EncoderMm[r]) != Bits(c.e[i]) ? 1 : 0;
                        differences += Bits(rows.S[r]) != Bits(c.s[i]) ? 1 : 0;
                        for (int k = 0; k < fibers; ++k)
                        {
                            differences += Bits(rows.Height[r, k]) != Bits(c.h[i * fibers + k]) ? 1 : 0;
                            differences += Bits(rows.Slope[r, k]) != Bits(c.g[i * fibers + k]) ? 1 : 0;
                            differences += Bits(rows.Truth[r, k]) != Bits(c.truth[i * fibers + k]) ? 1 : 0;
                            differences += (rows.Valid[r, k] ? 1 : 0) != c.v[i * fibers + k] ? 1 : 0;
                        }
                    }
                }
                byte[,] frame = line.NextFrame().Mono8();
                int pixelDifferences = 0;
                for (int v = 0; v < line.FrameHeight; ++v)
                    for (int u = 0; u < line.FrameWidth; ++u)
                        pixelDifferences += frame[v, u] != c.frame[v * line.FrameWidth + u] ? 1 : 0;
                output.WriteLine($"{(roi ? "ROI" : "reference")} sensor: {blocks * count} rows x {fibers} fibers " +
                                 $"compared with the C library: {differences} values differ; frame: {pixelDifferences} pixels differ");
                Assert.Equal(0, differences);
                Assert.Equal(0, pixelDifferences);
                Assert.NotEqual(c.h[5], c.truth[5]);  // the noise is really there
            }
        }

        private static long Bits(double value) => BitConverter.DoubleToInt64Bits(value);

        [Fact]
        public void TwoLinesOnTwoThreadsMatchSerialRunsBitwise()
        {
            using var calib = SmallSensor();
            (SimulatedRows, byte[,]) Run(uint seed)
            {
                using var options = Noisy(seed);
                using var line = new SimulatedLine(calib, options);  // one finished calibration, shared
                line.AddDefect(DefectKind.CentreBuckle, 12, 1800);
                SimulatedRows rows = line.NextRows(100);
                for (int block = 1; block < 20; ++block)
                    rows = line.NextRows(100);
                return (rows, line.NextFrame().Mono8());
            }
            var serial = new[] { Run(21), Run(22) };
            var parallel = new (SimulatedRows, byte[,])[2];
            var errors = new Exception[2];
            using var start = new Barrier(2);
            var threads = new Thread[2];
            for (int t = 0; t < 2; ++t)
            {
                int which = t;
                threads[t] = new Thread(() =>
                {
                    try
                    {
                        start.SignalAndWait();
                        parallel[which] = Run((uint)(21 + which));
                    }
                    catch (Exception e)
                    {
                        errors[which] = e;
                    }
                });
                threads[t].Start();
            }
            foreach (var thread in threads)
                thread.Join();
            Assert.Null(errors[0]);
            Assert.Null(errors[1]);
            for (int t = 0; t < 2; ++t)
            {
                Sheet.AssertBitwise(serial[t].Item1.Height, parallel[t].Item1.Height);
                Sheet.AssertBitwise(serial[t].Item1.Slope, parallel[t].Item1.Slope);
                Assert.Equal(serial[t].Item1.EncoderMm, parallel[t].Item1.EncoderMm);
                Assert.Equal(serial[t].Item2, parallel[t].Item2);
            }
            Assert.NotEqual(serial[0].Item1.Height[0, 0], serial[1].Item1.Height[0, 0]);  // two different lines
        }

        /// <summary>Creates a line from a calibration nobody else holds and
        /// returns a weak reference to that calibration.</summary>
        [MethodImpl(MethodImplOptions.NoInlining)]
        private static SimulatedLine LineOwningTheOnlyReference(out WeakReference calibration)
        {
            var calib = SmallSensor();
            calibration = new WeakReference(calib);
            return new SimulatedLine(calib);
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static WeakReference Abandoned()
        {
            var calib = SmallSensor();
            new SimulatedLine(calib);  // not kept
            return new WeakReference(calib);
        }

        private static void CollectEverything()
        {
            for (int i = 0; i < 3; ++i)
            {
                GC.Collect();
                GC.WaitForPendingFinalizers();
            }
        }

        [Fact]
        public void TheLineKeepsItsCalibrationAlive()
        {
            long calibsBefore = CalibHandle.Live;
            SimulatedLine line = LineOwningTheOnlyReference(out WeakReference calibration);
            CollectEverything();
            Assert.True(calibration.IsAlive, "the calibration was collected while its line lives");
            var held = Assert.IsType<Calibration>(calibration.Target);
            Assert.Same(held, line.Calibration);
            Assert.True(line.Calibration.IsFinished);  // not finalized
            line.AddDefect(DefectKind.Bow, 1, 1000);
            Assert.Equal(21, line.NextRows(10).Fibers);
            Assert.Equal(calibsBefore + 1, CalibHandle.Live);
            held = null;
            line.Dispose();
            // The control: without a line holding it, the same calibration is collected.
            WeakReference orphan = Abandoned();
            CollectEverything();
            Assert.False(orphan.IsAlive, "a calibration nobody holds survived the collection");
            GC.KeepAlive(line);
        }

        [Fact]
        public void ErrorsMapToTheirExceptions()
        {
            using var unfinished = new Calibration();
            var state = Assert.Throws<FlatlineStateException>(() => new SimulatedLine(unfinished));
            Assert.Contains("'calib' is not finished", state.Message);
            using var calib = SmallSensor();
            using var options = new FlatlineOptions();
            options["sim_bit_depth"] = 9;
            var invalid = Assert.Throws<InvalidArgumentException>(() => new SimulatedLine(calib, options));
            Assert.Contains("'sim_bit_depth' = 9", invalid.Message);
            using var line = new SimulatedLine(calib);
            invalid = Assert.Throws<InvalidArgumentException>(() => line.AddDefect(DefectKind.Bow, 1, -5));
            Assert.Contains("'period_mm' = -5", invalid.Message);
            invalid = Assert.Throws<InvalidArgumentException>(() => line.AddDefect((DefectKind)99, 1, 1));
            Assert.Contains("'kind' = 99", invalid.Message);
            invalid = Assert.Throws<InvalidArgumentException>(() =>
                line.SetHeightMap(new double[,] { { 0, 1 }, { double.NaN, 3 } }, 0, 1, 0, 1));
            Assert.Contains("'heights[2]'", invalid.Message);
            invalid = Assert.Throws<InvalidArgumentException>(() => line.SetHeightMap(new double[2, 2], 0, 0, 0, 1));
            Assert.Contains("'ds_mm' = 0", invalid.Message);
            for (int i = 0; i < 64; ++i)
                line.AddDefect(DefectKind.Flat, 0);
            Assert.Throws<BufferFullException>(() => line.AddDefect(DefectKind.Bow, 1));
            // Shapes are checked in C#, before the native call.
            Assert.Equal("heights", Assert.Throws<ArgumentException>(() => line.SetHeightMap(new double[1, 5], 0, 1, 0, 1)).ParamName);
            Assert.Equal("rows", Assert.Throws<ArgumentOutOfRangeException>(() => line.NextRows(0)).ParamName);
            // The line is still usable.
            line.ClearSheet();
            Assert.Equal(0.0, line.NextRows(3).Truth[2, 7]);
        }

        [Fact]
        public void DisposeIsImmediateIdempotentAndFinal()
        {
            using var calib = SmallSensor();
            Finalizers.Settle();
            long before = SimHandle.Live;
            var line = new SimulatedLine(calib);
            Assert.Equal(before + 1, SimHandle.Live);
            line.Dispose();
            Assert.Equal(before, SimHandle.Live);
            line.Dispose();
            Assert.Equal(before, SimHandle.Live);
            Assert.Throws<ObjectDisposedException>(() => line.NextRows(1));
            Assert.Throws<ObjectDisposedException>(() => line.NextFrame());
            Assert.Throws<ObjectDisposedException>(() => line.NextFrame(new byte[128, 2048]));
            Assert.Throws<ObjectDisposedException>(() => line.AddDefect(DefectKind.Bow, 1));
            Assert.Throws<ObjectDisposedException>(() => line.ClearSheet());
            Assert.Throws<ObjectDisposedException>(() => line.Surface(0, 0));
            Assert.Throws<ObjectDisposedException>(() => line.Rewind());
            Assert.Equal(21, line.Fibers);  // plain managed state stays readable
            // The caller's calibration is the caller's: still alive and usable.
            Assert.True(calib.IsFinished);
            // A calibration disposed after creating a line does not stop it
            // (the native simulator copied it).
            var own = SmallSensor();
            using var second = new SimulatedLine(own);
            own.Dispose();
            Assert.Equal(10, second.NextRows(10).Rows);
            // The reference calibration a default line made for itself goes with it.
            Finalizers.Settle();
            long calibs = CalibHandle.Live;
            var byDefault = new SimulatedLine();
            Assert.Equal(calibs + 1, CalibHandle.Live);
            byDefault.Dispose();
            Assert.Equal(calibs, CalibHandle.Live);
        }
    }
}
