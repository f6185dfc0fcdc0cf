// SPDX-License-Identifier: Apache-2.0
using System;
using Xunit;

namespace Flatline.Tests
{
    public class ReconstructorTests
    {
        private readonly ITestOutputHelper output;
        public ReconstructorTests(ITestOutputHelper output) => this.output = output;

        // 12 sin(2 pi s / 1800) seen by two lasers 100 mm apart, a row every 5 mm.
        private static Sheet SineSheet(int rows = 2400) => Sheet.Measure(Sheet.Sine, rows, 1, 0.0, 5.0);

        [Fact]
        public void NoiseFreeSineReconstructsWithinAMicronInBatch()
        {
            var sheet = SineSheet();
            var result = Library.Reconstruct(sheet.S, sheet.Height, sheet.Slope);
            double error = Sheet.MaxError(result.Z, sheet.TrueZ);
            output.WriteLine($"batch sine: max error {error:E2} mm");
            // The cubic Hermite interpolation error at 100 mm knots is
            // h^4/384 max|z''''| = 4.6e-4 mm for this sine; the fit does no worse.
            Assert.True(error < 1e-3, $"max error {error} mm");
        }

        [Fact]
        public void NoiseFreeSineReconstructsWithinAMicronStreamed()
        {
            var sheet = SineSheet();
            using var recon = new Reconstructor(1);
            var result = Sheet.Stream(recon, sheet, 37);
            Assert.Equal(sheet.S, result.S);
            double error = Sheet.MaxError(result.Z, sheet.TrueZ);
            output.WriteLine($"streamed sine: max error {error:E2} mm");
            Assert.True(error < 1e-3, $"max error {error} mm");
        }

        [Fact]
        public void RowsComeOutAfterTheLagAndAllAfterEndSheet()
        {
            using var options = new FlatlineOptions { LagKnots = 8 };
            using var recon = new Reconstructor(2, options);
            Assert.Equal(2, recon.Fibers);
            Assert.Equal(0, recon.Ready);
            var sheet = Sheet.Measure(Sheet.Waves, 300, 2, 0.0, 10.0);
            recon.Push(Sheet.Slice(sheet.S, 0, 50), Sheet.Slice(sheet.Height, 0, 50), Sheet.Slice(sheet.Slope, 0, 50));
            // 50 rows = 500 mm: less than the lag of 8 knots * 100 mm + 100 mm.
            Assert.Equal(0, recon.Ready);
            Assert.Equal(0, recon.Pull().Rows);
            recon.Push(Sheet.Slice(sheet.S, 50, 250), Sheet.Slice(sheet.Height, 50, 250), Sheet.Slice(sheet.Slope, 50, 250));
            int ready = recon.Ready;
            Assert.InRange(ready, 1, 299);
            var first = recon.Pull(5);
            Assert.Equal(5, first.Rows);
            Assert.Equal(Sheet.Slice(sheet.S, 0, 5), first.S);
            Assert.Equal(ready - 5, recon.Ready);
            recon.EndSheet();
            Assert.Equal(295, recon.Ready);
            var rest = recon.Pull();
            Assert.Equal(295, rest.Rows);
            Assert.Equal(sheet.S[299], rest.S[294]);
            Assert.Equal(0, recon.Ready);
            Assert.True(Sheet.MaxError(rest.Z, Sheet.Slice(sheet.TrueZ, 5, 295)) < 0.01);
        }

        [Fact]
        public void PeekGivesThePendingRowsProvisionallyAndChangesNothing()
        {
            var sheet = SineSheet();
            using var a = new Reconstructor(1);
            using var b = new Reconstructor(1);
            a.Push(Sheet.Slice(sheet.S, 0, 800), Sheet.Slice(sheet.Height, 0, 800), Sheet.Slice(sheet.Slope, 0, 800));
            b.Push(Sheet.Slice(sheet.S, 0, 800), Sheet.Slice(sheet.Height, 0, 800), Sheet.Slice(sheet.Slope, 0, 800));
            var firstA = a.Pull();
            var firstB = b.Pull();
            Assert.Equal(800 - firstA.Rows, a.Pending);
            var peeked = a.Peek();
            Assert.Equal(a.Pending, peeked.Rows);
            Assert.Equal(Sheet.Slice(sheet.S, firstA.Rows, 800 - firstA.Rows), peeked.S);
            // Noise-free: the provisional rows are already the spline, within
            // the 1 um of the final ones (the spline's own error is 0.46 um).
            double error = Sheet.MaxError(peeked.Z, Sheet.Slice(sheet.TrueZ, firstA.Rows, 800 - firstA.Rows));
            output.WriteLine($"provisional sine rows: max error {error:E2} mm");
            Assert.True(error < 1e-3, $"max error {error} mm");
            Assert.Equal(2, a.Peek(2).Rows);
            a.EndSheet();
            b.EndSheet();
            Assert.Equal(0, a.Pending);
            Assert.Equal(0, a.Peek().Rows);
            // Nothing pull gives changed.
            Assert.Equal(b.Pull().Z, a.Pull().Z);
            Assert.Equal(firstB.Z, firstA.Z);
            Assert.Throws<ArgumentOutOfRangeException>(() => a.Peek(-1));
        }

        [Fact]
        public void SingleRowPushesEqualOneBlockBitwise()
        {
            var sheet = Sheet.Measure(Sheet.Waves, 200, 3, 500.0, 8.0, vibrationSigma: 2.5);
            using var options = new FlatlineOptions { LagKnots = 4 };
            using var block = new Reconstructor(3, options);
            using var single = new Reconstructor(3, options);
            block.Push(sheet.S, sheet.Height, sheet.Slope);
            block.EndSheet();
            for (int r = 0; r < sheet.Rows; ++r)
            {
                var h = new double[3];
                var g = new double[3];
                for (int k = 0; k < 3; ++k)
                {
                    h[k] = sheet.Height[r, k];
                    g[k] = sheet.Slope[r, k];
                }
                single.Push(sheet.S[r], h, g);
            }
            single.EndSheet();
            Sheet.AssertBitwise(block.Pull().Z, single.Pull().Z);
        }

        [Fact]
        public void InvalidSamplesAreFlaggedAndAFiberWithoutDataIsNaN()
        {
            var sheet = Sheet.Measure(Sheet.Waves, 120, 3, 0.0, 10.0);
            var valid = new bool[120, 3];
            for (int r = 0; r < 120; ++r)
            {
                valid[r, 0] = r != 60;             // one missing sample
                valid[r, 1] = r < 40 || r >= 80;   // a 400 mm hole, longer than max_gap
                valid[r, 2] = false;               // never seen
            }
            var result = Library.Reconstruct(sheet.S, sheet.Height, sheet.Slope, valid);
            Assert.Equal(ReconFlags.None, result.FlagsAt(59, 0));
            Assert.Equal(ReconFlags.InvalidInput, result.FlagsAt(60, 0));
            Assert.True(Math.Abs(result.Z[60, 0] - sheet.TrueZ[60, 0]) < 0.05);
            Assert.Equal(ReconFlags.InvalidInput | ReconFlags.Gap, result.FlagsAt(60, 1));
            Assert.Equal(ReconFlags.None, result.FlagsAt(30, 1));
            Assert.True(result.FlagsAt(10, 2).HasFlag(ReconFlags.NoData));
            Assert.True(double.IsNaN(result.Z[10, 2]));
            Assert.False(double.IsNaN(result.Z[10, 0]));

            // The same mask through the streaming reconstructor.
            using var recon = new Reconstructor(3);
            var streamed = Sheet.Stream(recon, sheet, 25, valid);
            Assert.Equal(ReconFlags.InvalidInput, streamed.FlagsAt(60, 0));
            Assert.True(double.IsNaN(streamed.Z[10, 2]));
        }

        [Fact]
        public void BoundaryCarriesTheLastKnotIntoTheNextSheet()
        {
            var sheet = SineSheet(1200);
            using var recon = new Reconstructor(1);
            Sheet.Stream(recon, sheet, 100);
            var boundary = recon.Boundary();
            // The last knot is the one at or past the front laser of the last row.
            Assert.InRange(boundary.S, sheet.S[^1] + 50.0, sheet.S[^1] + 150.0);
            Assert.Single(boundary.Height);
            Assert.Single(boundary.Slope);
            Assert.True(Math.Abs(boundary.Height[0] - Sheet.Sine(boundary.S, 0)) < 1e-3);
            double trueSlope = 12.0 * 2 * Math.PI / 1800.0 * Math.Cos(2 * Math.PI * boundary.S / 1800.0);
            Assert.True(Math.Abs(boundary.Slope[0] - trueSlope) < 1e-4);
            // The next sheet continues; reset drops the carry-over.
            var next = Sheet.Measure(Sheet.Sine, 200, 1, sheet.S[^1] + 5.0, 5.0);
            recon.Push(next.S, next.Height, next.Slope);
            recon.Reset();
            Assert.Equal(0, recon.Ready);
            Assert.Throws<FlatlineStateException>(() => recon.Boundary());
            Assert.Throws<FlatlineStateException>(() => recon.Pull());
        }

        [Fact]
        public void WrongShapesThrowArgumentExceptionBeforeTheNativeCall()
        {
            using var recon = new Reconstructor(4);
            var s = new[] { 0.0, 1.0, 2.0 };
            Assert.Equal("height", Assert.Throws<ArgumentException>(() =>
                recon.Push(s, new double[3, 3], new double[3, 4])).ParamName);
            Assert.Equal("slope", Assert.Throws<ArgumentException>(() =>
                recon.Push(s, new double[3, 4], new double[2, 4])).ParamName);
            Assert.Equal("valid", Assert.Throws<ArgumentException>(() =>
                recon.Push(s, new double[3, 4], new double[3, 4], new bool[3, 5])).ParamName);
            Assert.Equal("s", Assert.Throws<ArgumentException>(() =>
                recon.Push(new double[0], new double[0, 4], new double[0, 4])).ParamName);
            Assert.Throws<ArgumentNullException>(() => recon.Push(s, null!, new double[3, 4]));  // null on purpose: the check under test
            Assert.Equal("height", Assert.Throws<ArgumentException>(() =>
                recon.Push(0.0, new double[3], new double[4])).ParamName);
            Assert.Equal("valid", Assert.Throws<ArgumentException>(() =>
                recon.Push(0.0, new double[4], new double[4], new bool[2])).ParamName);
            Assert.Throws<ArgumentOutOfRangeException>(() => recon.Pull(-1));
            Assert.Throws<ArgumentOutOfRangeException>(() => new Reconstructor(-3));
            // None of these reached the C library: still nothing pushed.
            Assert.Throws<FlatlineStateException>(() => recon.Pull());
        }

        // The reference camera with its lasers 80 mm apart (offsets -40, +40
        // mm), 41 fibers 50 mm apart. The simulator's profile rows use only
        // the offsets (the homographies scale the peak noise, off here), so
        // the reference homographies serve.
        private static Calibration Sensor80mm()
        {
            using var reference = Calibration.Reference(892, 256, -1000, 50, 41);
            var calib = new Calibration();
            calib.SetFrameSize(reference.FrameWidth, reference.FrameHeight);
            calib.Intrinsics = reference.Intrinsics;
            for (int laser = 0; laser < 2; ++laser)
                calib.SetHomography(laser, reference.GetHomography(laser));
            calib.SetLaserOffset(0, -40);
            calib.SetLaserOffset(1, 40);
            calib.EncoderScale = reference.EncoderScale;
            calib.FiberGrid = reference.FiberGrid;
            calib.Finish();
            return calib;
        }

        [Fact]
        public void FromACalibrationTakesItsSpacingAndFibers()
        {
            using var calib = Sensor80mm();
            Assert.Equal(80.0, calib.LaserSpacing);
            using (var options = new FlatlineOptions { LagKnots = 8 })
            using (var recon = new Reconstructor(calib, options))
            {
                Assert.Equal(41, recon.Fibers);
                Assert.Equal(80.0, recon.GetOption("laser_spacing"));
                Assert.Equal(80.0, recon.GetOption("knot_spacing"));  // follows the sensor
                Assert.Equal(8.0, recon.GetOption("lag_knots"));
            }
            using (var agree = new FlatlineOptions { LaserSpacing = 80 })
            using (var recon = new Reconstructor(calib, agree))
                Assert.Equal(80.0, recon.GetOption("laser_spacing"));
            using (var disagree = new FlatlineOptions { LaserSpacing = 100 })
            {
                var e = Assert.Throws<InvalidArgumentException>(() => new Reconstructor(calib, disagree));
                Assert.Contains("'laser_spacing' = 100 mm disagrees with the 80 mm", e.Message);
            }
            using var unfinished = new Calibration();
            Assert.Throws<FlatlineStateException>(() => new Reconstructor(unfinished));
            Assert.Throws<ArgumentNullException>(() => new Reconstructor((Calibration)null!));  // null on purpose: the check under test
        }

        // Noise-free simulated rows of the 80 mm sensor (5 mm waves at 400 mm
        // on the edges, an 8 mm buckle at 1600 mm in the centre): made from
        // the calibration the reconstructor is within what a cubic spline
        // with knots h = 80 mm apart can follow of a 400 mm wave,
        // h^4 / 384 max|z''''| = 0.032 mm (measured 0.016); left at the
        // 100 mm default it misreads the 400 mm waves' slopes by
        // sinc(pi 80/400) / sinc(pi 100/400) - 1 = 4 %, about 0.2 mm.
        [Fact]
        public void An80mmSensorIsReconstructedRightOnlyWithItsSpacing()
        {
            using var calib = Sensor80mm();
            SimulatedRows rows;
            using (var options = new FlatlineOptions().Set("sim_seed", 3))
            using (var line = new SimulatedLine(calib, options))
            {
                line.AddDefect(DefectKind.CentreBuckle, 8, 1600);
                line.AddDefect(DefectKind.WavyEdgeBoth, 5, 400);
                rows = line.NextRows(1200);
            }
            double Error(Reconstructor recon)
            {
                recon.Push(rows.S, rows.Height, rows.Slope, rows.Valid);
                recon.EndSheet();
                var result = recon.Pull();
                Assert.Equal(rows.S, result.S);
                return Sheet.MaxError(result.Z, rows.Truth);
            }
            using var fromCalib = new Reconstructor(calib);
            using var byDefault = new Reconstructor(calib.FiberGrid.Count);
            double right = Error(fromCalib), wrong = Error(byDefault);
            output.WriteLine($"80 mm sensor: max error {right:F4} mm; with the 100 mm default {wrong:F4} mm");
            Assert.True(right <= 0.032, $"max error {right} mm");
            Assert.True(wrong >= 0.1, $"max error with 100 mm {wrong} mm");
        }

        [Fact]
        public void DisposeIsImmediateIdempotentAndFinal()
        {
            Finalizers.Settle();
            long before = ReconHandle.Live;
            var recon = new Reconstructor(2);
            Assert.Equal(before + 1, ReconHandle.Live);
            recon.Push(0.0, new double[2], new double[2]);
            recon.Dispose();
            Assert.Equal(before, ReconHandle.Live);  // freed now, not at the next GC
            recon.Dispose();
            Assert.Equal(before, ReconHandle.Live);
            Assert.Throws<ObjectDisposedException>(() => recon.Push(1.0, new double[2], new double[2]));
            Assert.Throws<ObjectDisposedException>(() => recon.Push(new[] { 1.0 }, new double[1, 2], new double[1, 2]));
            Assert.Throws<ObjectDisposedException>(() => recon.Pull());
            Assert.Throws<ObjectDisposedException>(() => recon.Pull(3));
            Assert.Throws<ObjectDisposedException>(() => recon.Ready);
            Assert.Throws<ObjectDisposedException>(() => recon.EndSheet());
            Assert.Throws<ObjectDisposedException>(() => recon.Reset());
            Assert.Throws<ObjectDisposedException>(() => recon.Boundary());
            Assert.Throws<ObjectDisposedException>(() => recon.GetOption("lag_knots"));
            Assert.Equal(2, recon.Fibers);  // plain managed state stays readable
        }
    }
}
