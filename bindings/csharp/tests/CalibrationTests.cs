// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.IO;
using System.Linq;
using Xunit;

namespace Flatline.Tests
{
    public class CalibrationTests
    {
        private readonly ITestOutputHelper output;
        public CalibrationTests(ITestOutputHelper output) => this.output = output;

        private static string TempPath(string name) =>
            Path.Combine(Path.GetTempPath(), $"flatline-cs-{Environment.ProcessId}-{name}");

        /// <summary>The same sensor as `reference`, set part by part.</summary>
        private static Calibration FromParts(Calibration reference)
        {
            var calib = new Calibration();
            calib.SetFrameSize(reference.FrameWidth, reference.FrameHeight);
            calib.Intrinsics = reference.Intrinsics;
            for (int laser = 0; laser < Calibration.Lasers; ++laser)
            {
                calib.SetHomography(laser, reference.GetHomography(laser));
                calib.SetLaserOffset(laser, reference.GetLaserOffset(laser));
            }
            calib.EncoderScale = reference.EncoderScale;
            calib.FiberGrid = reference.FiberGrid;
            return calib;
        }

        [Fact]
        public void TheReferenceSensorHasItsDocumentedGeometry()
        {
            using var calib = Calibration.Reference();
            Assert.True(calib.IsFinished);
            Assert.Equal(2048, calib.FrameWidth);
            Assert.Equal(2048, calib.FrameHeight);
            var k = calib.Intrinsics;
            // f = 6 mm over 5.5 um pixels (sim.h), distortion of a 6 mm lens.
            Assert.Equal(6.0 / 0.0055, k.Fx, 9);
            Assert.Equal(k.Fx, k.Fy);
            Assert.Equal(1030.25, k.Cx);
            Assert.Equal(1019.75, k.Cy);
            Assert.Equal(new[] { -0.08, 0.012, 1.5e-4, -1e-4, -0.002, 0, 0, 0 }, k.Distortion);
            Assert.Equal(-50.0, calib.GetLaserOffset(0));
            Assert.Equal(50.0, calib.GetLaserOffset(1));
            Assert.Equal(100.0, calib.LaserSpacing);
            Assert.Equal(0.01, calib.EncoderScale);
            Assert.Equal(new FiberGrid(-1000, 2, 1001), calib.FiberGrid);
            Assert.Equal(1000.0, calib.FiberGrid.X(1000));
            // An ROI moves the principal point with it.
            using var roi = Calibration.Reference(892, 256, -500, 100, 11);
            Assert.Equal(256, roi.FrameHeight);
            Assert.Equal(1019.75 - 892, roi.Intrinsics.Cy);
            Assert.Equal(11, roi.FiberGrid.Count);
        }

        [Fact]
        public void APartByPartModelSavesTheSameTextAsTheOriginal()
        {
            using var reference = Calibration.Reference(892, 256, -500, 100, 11);
            using var calib = FromParts(reference);
            Assert.False(calib.IsFinished);
            calib.Finish();
            Assert.True(calib.IsFinished);
            string text = calib.ToText();
            Assert.Equal(reference.ToText(), text);
            Assert.StartsWith("{\n  \"format\": \"flatline-calibration\",\n  \"version\": 1,", text);
            Assert.Equal(1, Calibration.FormatVersion);
        }

        [Fact]
        public void SaveLoadAndParseRoundTripByteForByte()
        {
            using var reference = Calibration.Reference();
            string path = TempPath("roundtrip.json");
            try
            {
                reference.Save(path);
                string text = reference.ToText();
                Assert.Equal(text, File.ReadAllText(path));
                using var loaded = Calibration.Load(path);
                Assert.True(loaded.IsFinished);
                Assert.Equal(text, loaded.ToText());
                Assert.Equal(reference.Intrinsics, loaded.Intrinsics);
                using var parsed = Calibration.Parse(text);
                Assert.Equal(text, parsed.ToText());
                Sheet.AssertBitwise(reference.GetHomography(1), parsed.GetHomography(1));
            }
            finally
            {
                File.Delete(path);
            }
        }

        [Fact]
        public void ACorruptedFileIsAFormatErrorNamingTheField()
        {
            using var reference = Calibration.Reference();
            string path = TempPath("corrupt.json");
            try
            {
                reference.Save(path);
                string text = File.ReadAllText(path);
                Assert.Contains("\"width\": 2048", text);
                File.WriteAllText(path, text.Replace("\"width\": 2048", "\"width\": \"2048\""));
                var e = Assert.Throws<FlatlineFormatException>(() => Calibration.Load(path));
                Assert.Equal(Status.Format, e.Status);
                Assert.Contains("field 'frame.width' (line 5) must be a number, found a string", e.Message);
                Assert.Contains(path, e.Message);
                // A format error is also an I/O-family error, for callers catching both.
                Assert.IsAssignableFrom<FlatlineIOException>(e);
                // The same text through Parse; and a truncated one.
                string infinite = System.Text.RegularExpressions.Regex.Replace(text, "\"k1\": [^,]+,", "\"k1\": -inf,");
                Assert.NotEqual(text, infinite);
                e = Assert.Throws<FlatlineFormatException>(() => Calibration.Parse(infinite));
                Assert.Contains("field 'camera.distortion.k1' is infinite", e.Message);
                e = Assert.Throws<FlatlineFormatException>(() => Calibration.Parse(text.Substring(0, text.Length / 2)));
                Assert.Contains("truncated", e.Message);
            }
            finally
            {
                File.Delete(path);
            }
        }

        [Fact]
        public void AMissingFileIsAnIOError()
        {
            string path = TempPath("does-not-exist.json");
            var e = Assert.Throws<FlatlineIOException>(() => Calibration.Load(path));
            Assert.Equal(typeof(FlatlineIOException), e.GetType());  // not a format error
            Assert.Equal(Status.IO, e.Status);
            Assert.Contains("cannot open", e.Message);
            Assert.Contains(path, e.Message);
            // Writing into a folder that does not exist is an I/O error too.
            using var reference = Calibration.Reference(892, 256, -500, 100, 11);
            var w = Assert.Throws<FlatlineIOException>(() => reference.Save(Path.Combine(path, "sub", "x.json")));
            Assert.Equal(Status.IO, w.Status);
        }

        [Fact]
        public void AFinishedModelRefusesEverySetterAndStaysUsable()
        {
            using var calib = Calibration.Reference(892, 256, -500, 100, 11);
            string before = calib.ToText();
            var intrinsics = calib.Intrinsics;
            var setters = new Action[]
            {
                () => calib.SetFrameSize(100, 100),
                () => calib.Intrinsics = intrinsics,
                () => calib.SetHomography(0, calib.GetHomography(1)),
                () => calib.SetLaserOffset(1, 40),
                () => calib.EncoderScale = 0.02,
                () => calib.FiberGrid = new FiberGrid(0, 1, 3),
                () => calib.Finish(),
            };
            foreach (var set in setters)
            {
                var e = Assert.Throws<FlatlineStateException>(set);
                Assert.Equal(Status.State, e.Status);
            }
            var state = Assert.Throws<FlatlineStateException>(() => calib.EncoderScale = 0.02);
            Assert.Equal("flt_calib_set_encoder_scale: the calibration is finished and immutable; " +
                         "create a new one to change it", state.Message);
            Assert.Equal(before, calib.ToText());
        }

        [Fact]
        public void AnUnfinishedModelNamesWhatIsMissing()
        {
            using var calib = new Calibration();
            Assert.False(calib.IsFinished);
            Assert.Throws<FlatlineStateException>(() => calib.Intrinsics);
            Assert.Throws<FlatlineStateException>(() => calib.FrameWidth);
            Assert.Throws<FlatlineStateException>(() => calib.LaserSpacing);
            Assert.Throws<FlatlineStateException>(() => calib.ToText());
            Assert.Throws<FlatlineStateException>(() => calib.ImageToPlane(0, new double[1, 2]));
            var e = Assert.Throws<FlatlineStateException>(() => calib.Finish());
            Assert.Contains("the calibration lacks", e.Message);
            // Bad values are the C library's invalid arguments, named.
            var bad = Assert.Throws<InvalidArgumentException>(() => calib.EncoderScale = 0);
            Assert.Contains("encoder_mm_per_count", bad.Message);
            bad = Assert.Throws<InvalidArgumentException>(() => calib.Intrinsics = new CameraIntrinsics(-5, 5, 1, 1));
            Assert.Equal(Status.InvalidArgument, bad.Status);
            bad = Assert.Throws<InvalidArgumentException>(() =>
                calib.SetHomography(0, new double[,] { { 1, 2, 3 }, { 2, 4, 6 }, { 0, 0, 1 } }));
            Assert.Contains("not invertible", bad.Message);
            Assert.False(calib.IsFinished);
        }

        [Fact]
        public void WrongShapesThrowArgumentExceptionBeforeTheNativeCall()
        {
            // An unfinished model: had any of these reached the C library, it
            // would have answered FLT_ERR_STATE.
            using var calib = new Calibration();
            Assert.Equal("imagePx", Assert.Throws<ArgumentException>(() => calib.ImageToPlane(0, new double[4, 3])).ParamName);
            Assert.Equal("planeMm", Assert.Throws<ArgumentException>(() => calib.PlaneToImage(1, new double[4, 1])).ParamName);
            Assert.Equal("imagePx", Assert.Throws<ArgumentException>(() => calib.Undistort(new double[2, 4])).ParamName);
            Assert.Equal("planeMm", Assert.Throws<ArgumentException>(() =>
                calib.EstimateHomography(0, new double[6, 2], new double[5, 2])).ParamName);
            Assert.Equal("homography", Assert.Throws<ArgumentException>(() =>
                calib.SetHomography(0, new double[3, 2])).ParamName);
            Assert.Equal("laser", Assert.Throws<ArgumentOutOfRangeException>(() => calib.ImageToPlane(2, new double[1, 2])).ParamName);
            Assert.Equal("laser", Assert.Throws<ArgumentOutOfRangeException>(() => calib.GetLaserOffset(-1)).ParamName);
            Assert.Throws<ArgumentNullException>(() => calib.ImageToPlane(0, null!));  // null on purpose: the check under test
            calib.SetFrameSize(64, 48);
            var images = new List<byte[,]> { new byte[48, 64], new byte[48, 63] };
            var e = Assert.Throws<ArgumentException>(() =>
                calib.EstimateIntrinsics(images, CalibrationTarget.Chessboard, 9, 6, 30));
            Assert.Equal("images", e.ParamName);
            Assert.Contains("images[1] is [48, 63]", e.Message);
            Assert.Throws<ArgumentException>(() =>
                calib.EstimateIntrinsics(new List<byte[,]>(), CalibrationTarget.Chessboard, 9, 6, 30));
            Assert.Throws<FlatlineStateException>(() => calib.Intrinsics);  // still empty
        }

        [Fact]
        public void ImageAndPlaneMappingsInvertEachOther()
        {
            using var calib = Calibration.Reference();
            // Points across the plane: x over the strip, z +- 40 mm.
            var plane = new double[45, 2];
            for (int i = 0; i < 45; ++i)
            {
                plane[i, 0] = -900 + 40.0 * i;
                plane[i, 1] = -40 + 2.0 * (i % 41);
            }
            for (int laser = 0; laser < Calibration.Lasers; ++laser)
            {
                double[,] image = calib.PlaneToImage(laser, plane);
                double[,] back = calib.ImageToPlane(laser, image);
                double worst = 0;
                for (int i = 0; i < 45; ++i)
                    worst = Math.Max(worst, Math.Max(Math.Abs(back[i, 0] - plane[i, 0]), Math.Abs(back[i, 1] - plane[i, 1])));
                output.WriteLine($"laser {laser}: plane -> image -> plane worst {worst:E2} mm");
                // The undistortion's Newton solve converges to ~1e-9 px
                // (calib.h); at ~2 mm/px that is a few nm.
                Assert.True(worst < 1e-6, $"round trip off by {worst} mm");
            }
            // Where the header says the lines are at z = 0: near rows 1044 (laser 0) and 996 (laser 1).
            double[,] centre = calib.PlaneToImage(0, new double[,] { { 0, 0 } });
            Assert.InRange(centre[0, 1], 1040, 1048);
            Assert.InRange(calib.PlaneToImage(1, new double[,] { { 0, 0 } })[0, 1], 992, 1000);
            // A NaN point stays NaN; an empty batch is fine.
            double[,] nan = calib.ImageToPlane(0, new double[,] { { double.NaN, 5 } });
            Assert.True(double.IsNaN(nan[0, 0]) && double.IsNaN(nan[0, 1]));
            Assert.Empty(calib.ImageToPlane(1, new double[0, 2]));
            // Undistortion: the principal point is fixed; points outward move outward (barrel).
            double[,] u = calib.Undistort(new double[,] { { 1030.25, 1019.75 }, { 1830.25, 1019.75 } });
            Assert.Equal(1030.25, u[0, 0], 9);
            Assert.Equal(1019.75, u[0, 1], 9);
            Assert.True(u[1, 0] > 1830.25);
        }

        /// <summary>Exact correspondences from the reference's own plane_to_image.</summary>
        private static (double[,] image, double[,] plane) Correspondences(Calibration reference, int laser)
        {
            var plane = new double[60, 2];
            for (int i = 0; i < 60; ++i)
            {
                plane[i, 0] = -950 + 1900.0 * (i % 10) / 9;
                plane[i, 1] = -50 + 20.0 * (i / 10);
            }
            return (reference.PlaneToImage(laser, plane), plane);
        }

        [Fact]
        public void ExactCorrespondencesGiveTheHomographyBack()
        {
            using var reference = Calibration.Reference();
            using var calib = new Calibration();
            calib.Intrinsics = reference.Intrinsics;
            var (image, plane) = Correspondences(reference, 1);
            HomographyEstimate fit = calib.EstimateHomography(1, image, plane);
            output.WriteLine($"exact: rms {fit.RmsPx:E2} px, {fit.RmsMm:E2} mm");
            // Exact data: what is left is the undistortion's ~1e-9 px and rounding.
            Assert.True(fit.RmsPx < 1e-6, $"rms {fit.RmsPx} px");
            Assert.True(fit.RmsMm < 1e-5, $"rms {fit.RmsMm} mm");
            Assert.Equal(60, fit.ResidualPx.Length);
            Assert.Equal(60, fit.InlierCount);
            Assert.All(fit.ResidualMm, r => Assert.True(r < 1e-4));
            // The same map up to scale: compare H / H[2,2].
            double[,] truth = reference.GetHomography(1);
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c)
                {
                    double expected = truth[r, c] / truth[2, 2], got = fit.Homography[r, c] / fit.Homography[2, 2];
                    Assert.True(Math.Abs(got - expected) <= 1e-6 * Math.Max(1, Math.Abs(expected)),
                                $"H[{r},{c}] = {got}, expected {expected}");
                }
            Sheet.AssertBitwise(fit.Homography, calib.GetHomography(1));  // stored in the model
        }

        [Fact]
        public void RansacFlagsTheOutliers()
        {
            using var reference = Calibration.Reference();
            using var calib = new Calibration();
            calib.Intrinsics = reference.Intrinsics;
            var (image, plane) = Correspondences(reference, 0);
            int[] outliers = { 3, 17, 42 };
            foreach (int i in outliers)
                image[i, 1] += 25.0;  // 25 px off the line: a reflection taken for the line
            using var options = new FlatlineOptions { CalibRansac = true, CalibRansacThreshold = 1.0, CalibRansacSeed = 5 };
            HomographyEstimate fit = calib.EstimateHomography(0, image, plane, options);
            output.WriteLine($"ransac: {fit.InlierCount} inliers, rms {fit.RmsPx:E2} px");
            for (int i = 0; i < 60; ++i)
                Assert.Equal(!outliers.Contains(i), fit.Inlier[i]);
            Assert.True(fit.RmsPx < 1e-6);
            foreach (int i in outliers)
                Assert.InRange(fit.ResidualPx[i], 20.0, 30.0);
            // Without RANSAC the outliers drag the fit: every point is an inlier and the RMS grows.
            using var plain = new Calibration();
            plain.Intrinsics = reference.Intrinsics;
            HomographyEstimate dragged = plain.EstimateHomography(0, image, plane);
            Assert.Equal(60, dragged.InlierCount);
            Assert.True(dragged.RmsPx > 1.0, $"rms {dragged.RmsPx} px");
            // Too few points: the C library's invalid argument, the model unchanged.
            var e = Assert.Throws<InvalidArgumentException>(() =>
                plain.EstimateHomography(1, Sheet.Slice(image, 0, 3), Sheet.Slice(plane, 0, 3)));
            Assert.Contains("'count' = 3", e.Message);
            Assert.Throws<FlatlineStateException>(() => plain.GetHomography(1));
        }

        [Fact]
        public void ChessboardViewsGiveTheCamera()
        {
            var images = Chessboard.Poses.Select(Chessboard.Render).ToList();
            images.Insert(4, new byte[Chessboard.Height, Chessboard.Width]);  // a view without the target
            using var calib = new Calibration();
            calib.SetFrameSize(Chessboard.Width, Chessboard.Height);
            IntrinsicsEstimate fit = calib.EstimateIntrinsics(images, CalibrationTarget.Chessboard,
                                                              Chessboard.SquaresX - 1, Chessboard.SquaresY - 1,
                                                              Chessboard.SquareMm);
            var k = fit.Intrinsics;
            output.WriteLine($"chessboard: rms {fit.RmsPx:F4} px, {fit.ViewsUsed} of {images.Count} views; {k}");
            Assert.Equal(Chessboard.Poses.Length, fit.ViewsUsed);
            Assert.True(double.IsNaN(fit.ViewRmsPx[4]));
            Assert.Equal(k, calib.Intrinsics);
            // Focal length within 0.5 % and sub-0.1 px reprojection, as the C
            // test of the 2048 px camera; the 4 x 4 supersampled 8-bit edges
            // bias corners by a few hundredths of a pixel.
            Assert.True(Math.Abs(k.Fx / Chessboard.Focal - 1) < 0.005, $"fx {k.Fx}");
            Assert.True(Math.Abs(k.Fy / Chessboard.Focal - 1) < 0.005, $"fy {k.Fy}");
            Assert.True(fit.RmsPx < 0.1, $"rms {fit.RmsPx}");
            // Principal point within 1 % of the focal length.
            Assert.InRange(k.Cx, Chessboard.Cx - 7, Chessboard.Cx + 7);
            Assert.InRange(k.Cy, Chessboard.Cy - 7, Chessboard.Cy + 7);
            // Too few views: a numeric error, the model keeps its estimate.
            var e = Assert.Throws<NumericException>(() =>
                calib.EstimateIntrinsics(images.Take(2).ToList(), CalibrationTarget.Chessboard, 9, 6, 30));
            Assert.Contains("found in 2 of 2 views", e.Message);
            Assert.Equal(k, calib.Intrinsics);
        }

        [Fact]
        public void DisposeIsImmediateIdempotentAndFinal()
        {
            Finalizers.Settle();
            long before = CalibHandle.Live;
            var calib = Calibration.Reference(892, 256, -500, 100, 11);
            Assert.Equal(before + 1, CalibHandle.Live);
            calib.Dispose();
            Assert.Equal(before, CalibHandle.Live);
            calib.Dispose();
            Assert.Equal(before, CalibHandle.Live);
            Assert.Throws<ObjectDisposedException>(() => calib.IsFinished);
            Assert.Throws<ObjectDisposedException>(() => calib.Intrinsics);
            Assert.Throws<ObjectDisposedException>(() => calib.ToText());
            Assert.Throws<ObjectDisposedException>(() => calib.Save(TempPath("never.json")));
            Assert.Throws<ObjectDisposedException>(() => calib.ImageToPlane(0, new double[1, 2]));
            Assert.Throws<ObjectDisposedException>(() => calib.EncoderScale = 1);
            Assert.Throws<ObjectDisposedException>(() => calib.Finish());
            Assert.Throws<ObjectDisposedException>(() => new SimulatedLine(calib));
            Assert.False(File.Exists(TempPath("never.json")));
        }
    }
}
