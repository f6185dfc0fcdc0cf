// SPDX-License-Identifier: Apache-2.0
using System;
using System.Linq;
using System.Runtime.CompilerServices;
using System.Threading;
using Xunit;

namespace Flatline.Tests
{
    public class ExtractorTests
    {
        private readonly ITestOutputHelper output;
        public ExtractorTests(ITestOutputHelper output) => this.output = output;

        /// <summary>Rows 960..1087 of the reference sensor (both lines, +-50
        /// mm of height) and 101 fibers every 20 mm. The extractor fits a line
        /// through the columns within +-pitch of each fiber, so a fine grid
        /// keeps its curvature bias on this sheet to microns.</summary>
        private static Calibration Sensor() => Calibration.Reference(960, 128, -1000, 20, 101);

        /// <summary>A sheet smooth across the width (a centre buckle and a
        /// bow), with the simulator's default camera noise (speckle, shot
        /// noise, 8 bits).</summary>
        private static SimulatedLine Line(Calibration calib, FlatlineOptions? options = null)
        {
            var line = new SimulatedLine(calib, options);
            line.AddDefect(DefectKind.CentreBuckle, 12, 1800);
            line.AddDefect(DefectKind.Bow, 3, 2500);
            return line;
        }

        [Fact]
        public void FramesBecomeRowsOfTheTwoLasersHeights()
        {
            using var calib = Sensor();
            using var line = Line(calib);
            using var extractor = new Extractor(calib);
            Assert.Same(calib, extractor.Calibration);
            Assert.Equal(101, extractor.Fibers);
            Assert.Equal(2048, extractor.FrameWidth);
            Assert.Equal(128, extractor.FrameHeight);
            Assert.Throws<FlatlineStateException>(() => extractor.Band(0));  // automatic, no frame yet
            double worst = 0, sum2 = 0;
            int samples = 0, valid = 0;
            for (int f = 0; f < 10; ++f)
            {
                SimulatedFrame frame = line.NextFrame();
                ProfileRow row = extractor.Process(frame);
                Assert.Equal(frame.EncoderMm, row.EncoderMm);
                Assert.Equal(frame.EncoderMm, row.S, 12);  // offsets -50, +50: s = e
                double[,] z = extractor.LaserProfiles();
                for (int k = 0; k < row.Fibers; ++k)
                {
                    ++samples;
                    if (!row.Valid[k])
                    {
                        Assert.True(double.IsNaN(row.Height[k]) && double.IsNaN(row.Slope[k]));
                        continue;
                    }
                    ++valid;
                    // The row operators of extractor.h on the lasers' own z
                    // (laser 0 at offset -50 reads the larger s: it is ahead).
                    Assert.Equal((z[0, k] + z[1, k]) / 2, row.Height[k], 12);
                    Assert.Equal((z[0, k] - z[1, k]) / 100, row.Slope[k], 14);
                    double x = calib.FiberGrid.X(k);
                    double ahead = line.Surface(x, row.S + 50), behind = line.Surface(x, row.S - 50);
                    double error = row.Height[k] - (ahead + behind) / 2;
                    worst = Math.Max(worst, Math.Abs(error));
                    sum2 += error * error;
                }
            }
            double rms = Math.Sqrt(sum2 / valid);
            output.WriteLine($"extracted heights vs the sheet: rms {rms:F4} mm, worst {worst:F4} mm, " +
                             $"{valid} of {samples} fibers valid");
            // extractor.h's bound is 2 sigma <= 0.1 mm per laser (the C test
            // measures 0.059 on a rougher sheet); a row's height averages two
            // lasers. Measured here: RMS 0.010 mm, worst 0.027 mm over 1010
            // samples; 0.03 mm RMS and 0.1 mm at worst are three times that.
            Assert.True(rms < 0.03, $"rms {rms} mm");
            Assert.True(worst < 0.1, $"worst {worst} mm");
            Assert.True(valid >= 0.99 * samples, $"{valid} of {samples} valid");
            // The automatic bands found the lines: laser 1's above laser 0's.
            RowBand band0 = extractor.Band(0), band1 = extractor.Band(1);
            Assert.True(band1.FirstRow < band0.FirstRow);
            Assert.InRange(1044 - 960, band0.FirstRow, band0.FirstRow + band0.Rows);
            Assert.InRange(996 - 960, band1.FirstRow, band1.FirstRow + band1.Rows);
        }

        [Fact]
        public void PeaksAreTheLineCentresAndNaNWhereThereIsNone()
        {
            using var calib = Sensor();
            using var line = Line(calib);
            using var extractor = new Extractor(calib);
            var e = Assert.Throws<FlatlineStateException>(() => extractor.Peaks());
            Assert.Contains("no frame has been processed yet", e.Message);
            SimulatedFrame frame = line.NextFrame();
            extractor.Process(frame);
            double[,] peaks = extractor.Peaks();
            Assert.Equal(2, peaks.GetLength(0));
            Assert.Equal(2048, peaks.GetLength(1));
            double sum2 = 0;
            int found = 0;
            for (int laser = 0; laser < 2; ++laser)
                for (int u = 0; u < 2048; ++u)
                {
                    if (double.IsNaN(peaks[laser, u]))
                        continue;
                    ++found;
                    double d = peaks[laser, u] - frame.PeakRows[laser, u];
                    sum2 += d * d;
                }
            double rms = Math.Sqrt(sum2 / found);
            output.WriteLine($"peak rows vs the simulator's line centres: rms {rms:F4} px over {found} columns");
            // extractor.h's bound (the C test measures 1/37 .. 1/25 px).
            Assert.True(rms <= 1.0 / 16, $"rms {rms} px");
            Assert.True(found > 0.99 * 2 * 2048);
            // A dark frame: no peak anywhere, every fiber invalid.
            ProfileRow dark = extractor.Process(new byte[128, 2048], 1000.0);
            Assert.All(dark.Valid, v => Assert.False(v));
            Assert.All(dark.Height, h => Assert.True(double.IsNaN(h)));
            Assert.All(extractor.Peaks().Cast<double>(), p => Assert.True(double.IsNaN(p)));
        }

        [Fact]
        public void SixteenBitFramesGiveTheSameSheet()
        {
            using var calib = Sensor();
            using var options = new FlatlineOptions { SimBitDepth = 12 };
            using var line = Line(calib, options);
            using var extractor = new Extractor(calib);
            double worst = 0;
            for (int f = 0; f < 5; ++f)
            {
                SimulatedFrame frame = line.NextFrame();
                Assert.Equal(PixelFormat.Mono12, frame.Format);
                ProfileRow row = extractor.Process(Assert.IsType<ushort[,]>(frame.Pixels), PixelFormat.Mono12, frame.EncoderMm);
                for (int k = 0; k < row.Fibers; ++k)
                {
                    Assert.True(row.Valid[k]);
                    double x = calib.FiberGrid.X(k);
                    double expected = (line.Surface(x, row.S + 50) + line.Surface(x, row.S - 50)) / 2;
                    worst = Math.Max(worst, Math.Abs(row.Height[k] - expected));
                }
            }
            output.WriteLine($"Mono12: worst height error {worst:F4} mm");
            // As for 8 bits (measured 0.025 mm over 505 samples).
            Assert.True(worst < 0.1, $"worst {worst} mm");
        }

        [Fact]
        public void ReusedBuffersGiveTheSameRowsAndTwoExtractorsAgreeBitwise()
        {
            using var calib = Sensor();
            using var line = Line(calib);
            using var options = new FlatlineOptions
            {
                ExtractLaser0FirstRow = 1044 - 960 - 20, ExtractLaser0Rows = 40,
                ExtractLaser1FirstRow = 996 - 960 - 20, ExtractLaser1Rows = 40,
            };
            using var a = new Extractor(calib, options);
            using var b = new Extractor(calib, options);
            Assert.Equal(new RowBand(64, 40), a.Band(0));  // fixed bands: known before any frame
            var height = new double[101];
            var slope = new double[101];
            var valid = new bool[101];
            var pixels = new byte[128, 2048];
            for (int f = 0; f < 3; ++f)
            {
                double e = line.NextFrame(pixels);
                ProfileRow row = a.Process(pixels, e);
                double s = b.Process(pixels, e, height, slope, valid);
                Assert.Equal(row.S, s);
                Assert.Equal(row.Height, height);  // Assert.Equal on double[] compares exactly (NaN = NaN)
                Assert.Equal(row.Slope, slope);
                Assert.Equal(row.Valid, valid);
            }
            Sheet.AssertBitwise(a.Peaks(), b.Peaks());
        }

        [Fact]
        public void FramesStreamedThroughExtractorAndReconstructorGiveTheSheet()
        {
            // 3 m of strip, a frame every 5 mm, no vibration, camera noise.
            using var calib = Sensor();
            using var options = new FlatlineOptions { SimFrameSpacing = 5 };
            using var line = Line(calib, options);
            using var extractor = new Extractor(calib);
            using var recon = new Reconstructor(extractor.Fibers);
            var truth = new System.Collections.Generic.Dictionary<double, double[]>();
            double worst = 0;
            int rows = 0;
            void Check(ReconResult done)
            {
                for (int r = 0; r < done.Rows; ++r, ++rows)
                    for (int k = 0; k < done.Fibers; ++k)
                        worst = Math.Max(worst, Math.Abs(done.Z[r, k] - truth[done.S[r]][k]));
            }
            for (int f = 0; f < 600; ++f)
            {
                SimulatedFrame frame = line.NextFrame();
                ProfileRow row = extractor.Process(frame);
                truth[row.S] = frame.Truth;
                recon.Push(row.S, row.Height, row.Slope, row.Valid);
                Check(recon.Pull());
            }
            recon.EndSheet();
            Check(recon.Pull());
            output.WriteLine($"frames -> extractor -> reconstructor: {rows} rows, max error {worst:F3} mm");
            Assert.Equal(600, rows);
            // The spline averages the extracted rows' noise (about 0.01 mm per
            // row, above) over 20 frames per knot; measured 0.040 mm at worst.
            // 0.12 mm is three times that, and a quarter of the C end-to-end
            // test's 0.5 mm bound for a rougher sheet with vibration.
            Assert.True(worst < 0.12, $"max error {worst} mm");
        }

        [Fact]
        public void WrongSizesThrowArgumentExceptionBeforeTheNativeCall()
        {
            using var calib = Sensor();
            using var extractor = new Extractor(calib);
            Assert.Equal("frame", Assert.Throws<ArgumentException>(() => extractor.Process(new byte[127, 2048], 0)).ParamName);
            Assert.Equal("frame", Assert.Throws<ArgumentException>(() =>
                extractor.Process(new ushort[128, 2047], PixelFormat.Mono16, 0)).ParamName);
            Assert.Equal("format", Assert.Throws<ArgumentException>(() =>
                extractor.Process(new ushort[128, 2048], PixelFormat.Mono8, 0)).ParamName);
            Assert.Equal("height", Assert.Throws<ArgumentException>(() =>
                extractor.Process(new byte[128, 2048], 0, new double[100], new double[101])).ParamName);
            Assert.Equal("valid", Assert.Throws<ArgumentException>(() =>
                extractor.Process(new byte[128, 2048], 0, new double[101], new double[101], new bool[102])).ParamName);
            Assert.Throws<ArgumentNullException>(() => extractor.Process((byte[,])null!, 0));  // null on purpose: the check under test
            Assert.Equal("laser", Assert.Throws<ArgumentOutOfRangeException>(() => extractor.Band(2)).ParamName);
            // None reached the C library: no frame was processed.
            Assert.Throws<FlatlineStateException>(() => extractor.Peaks());
        }

        [Fact]
        public void ErrorsMapToTheirExceptions()
        {
            using var unfinished = new Calibration();
            var state = Assert.Throws<FlatlineStateException>(() => new Extractor(unfinished));
            Assert.Contains("'calib' is not finished", state.Message);
            Assert.Throws<ArgumentNullException>(() => new Extractor(null!));  // null on purpose: the check under test
            using var calib = Sensor();
            using var even = new FlatlineOptions { ExtractSgWindow = 10 };
            var invalid = Assert.Throws<InvalidArgumentException>(() => new Extractor(calib, even));
            Assert.Contains("'extract_sg_window' = 10 must be odd", invalid.Message);
            using var outside = new FlatlineOptions { ExtractLaser0FirstRow = 100, ExtractLaser0Rows = 40, ExtractLaser1Rows = 40 };
            invalid = Assert.Throws<InvalidArgumentException>(() => new Extractor(calib, outside));
            Assert.Contains("exceeds the frame height 128", invalid.Message);
            using var extractor = new Extractor(calib);
            invalid = Assert.Throws<InvalidArgumentException>(() => extractor.Process(new byte[128, 2048], double.NaN));
            Assert.Contains("argument 'encoder_mm' = ", invalid.Message);
            Assert.Contains("is not finite", invalid.Message);
            // An automatic band needs two lines in the first frame.
            var numeric = Assert.Throws<NumericException>(() => extractor.Process(new byte[128, 2048], 0));
            Assert.Equal(Status.Numeric, numeric.Status);
            // ... and the next frame tries again: the extractor is still usable.
            using var line = Line(calib);
            Assert.True(extractor.Process(line.NextFrame()).Valid.All(v => v));
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static Extractor ExtractorOwningTheOnlyReference(out WeakReference calibration)
        {
            var calib = Sensor();
            calibration = new WeakReference(calib);
            return new Extractor(calib);
        }

        [Fact]
        public void TheExtractorKeepsItsCalibrationAlive()
        {
            Extractor extractor = ExtractorOwningTheOnlyReference(out WeakReference calibration);
            for (int i = 0; i < 3; ++i)
            {
                GC.Collect();
                GC.WaitForPendingFinalizers();
            }
            Assert.True(calibration.IsAlive, "the calibration was collected while its extractor lives");
            Assert.True(extractor.Calibration.IsFinished);
            using var line = Line(extractor.Calibration);
            Assert.Equal(101, extractor.Process(line.NextFrame()).Fibers);
            extractor.Dispose();
        }

        [Fact]
        public void DisposeIsImmediateIdempotentAndFinal()
        {
            using var calib = Sensor();
            Finalizers.Settle();
            long before = ExtractorHandle.Live;
            var extractor = new Extractor(calib);
            Assert.Equal(before + 1, ExtractorHandle.Live);
            extractor.Dispose();
            Assert.Equal(before, ExtractorHandle.Live);
            extractor.Dispose();
            Assert.Equal(before, ExtractorHandle.Live);
            Assert.Throws<ObjectDisposedException>(() => extractor.Process(new byte[128, 2048], 0));
            Assert.Throws<ObjectDisposedException>(() => extractor.Process(new ushort[128, 2048], PixelFormat.Mono16, 0));
            Assert.Throws<ObjectDisposedException>(() => extractor.Peaks());
            Assert.Throws<ObjectDisposedException>(() => extractor.LaserProfiles());
            Assert.Throws<ObjectDisposedException>(() => extractor.Band(0));
            Assert.Equal(101, extractor.Fibers);
            Assert.True(calib.IsFinished);  // the caller's calibration is untouched
        }

        [Fact]
        public void TwoExtractorsOnTwoThreadsMatchSerialRunsBitwise()
        {
            using var calib = Sensor();
            using var line = Line(calib);
            var frames = Enumerable.Range(0, 8).Select(_ => line.NextFrame()).ToArray();
            double[][] Run(int first)
            {
                using var extractor = new Extractor(calib);
                return Enumerable.Range(0, 4).Select(i => extractor.Process(frames[first + i]).Height).ToArray();
            }
            var serial = new[] { Run(0), Run(4) };
            var parallel = new double[2][][];
            var errors = new Exception[2];
            using var start = new Barrier(2);
            var threads = Enumerable.Range(0, 2).Select(t => new Thread(() =>
            {
                try
                {
                    start.SignalAndWait();
                    parallel[t] = Run(4 * t);
                }
                catch (Exception e)
                {
                    errors[t] = e;
                }
            })).ToArray();
            foreach (var thread in threads)
                thread.Start();
            foreach (var thread in threads)
                thread.Join();
            Assert.Null(errors[0]);
            Assert.Null(errors[1]);
            for (int t = 0; t < 2; ++t)
                for (int i = 0; i < 4; ++i)
                    Assert.Equal(serial[t][i], parallel[t][i]);
        }
    }
}
