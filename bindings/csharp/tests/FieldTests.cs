// SPDX-License-Identifier: Apache-2.0
using System;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>The line in the field from C#: the strip's edges, the
    /// off-strip flag, saturated lines and zones on the strip. The accuracy
    /// is measured in C (tests/c/test_field.c, test_flatness_strip.c); these
    /// tests check that every new call is reachable, agrees with the
    /// simulator's truth and refuses bad input.</summary>
    public class FieldTests
    {
        // The C field tests' sensor: rows 892..1147 of the reference camera,
        // 1251 fibers at 2 mm (x = -1250 .. 1250 mm), bands around both lines.
        private const int Fibers = 1251;
        private const double FirstX = -1250, Pitch = 2;
        private static Calibration Sensor() => Calibration.Reference(892, 256, FirstX, Pitch, Fibers);

        private static Extractor FieldExtractor(Calibration calib)
        {
            using var options = new FlatlineOptions
            {
                ExtractLaser0FirstRow = 128, ExtractLaser0Rows = 112,
                ExtractLaser1FirstRow = 64, ExtractLaser1Rows = 64,
            };
            return new Extractor(calib, options);
        }

        [Fact]
        public void EdgesAndFiberFlagsMatchTheSimulatorsTruth()
        {
            // A 1500 mm strip 120 mm off centre over the roller table, no
            // motion noise. The C test measures 0.07-0.10 mm RMS under the
            // reference noise; 1 mm per edge (the accuracy goal) and 2 mm for
            // the width still catch mixed-up lasers, edges or units.
            using var calib = Sensor();
            using var simOptions = new FlatlineOptions
            {
                SimSurround = SimSurround.RollerTable, SimStripWidth = 1500, SimStripOffset = 120,
                SimFrameSpacing = 300,
            };
            using var line = new SimulatedLine(calib, simOptions);
            line.AddDefect(DefectKind.CentreBuckle, 4, 2100);
            using var extractor = FieldExtractor(calib);
            for (int f = 0; f < 3; ++f)
            {
                SimulatedFrame frame = line.NextFrame();
                extractor.Process(frame);
                for (int laser = 0; laser <= 2; ++laser)
                {
                    SimulatedEdges truth = line.StripEdges(new[] { frame.EncoderMm }, laser);
                    Assert.True(truth.Present[0]);
                    StripEdges edges = extractor.Strip(laser);
                    Assert.Equal(StripFlags.None, edges.Flags);
                    Assert.InRange(edges.LeftMm - truth.LeftMm[0], -1.0, 1.0);
                    Assert.InRange(edges.RightMm - truth.RightMm[0], -1.0, 1.0);
                    Assert.InRange(edges.WidthMm - (truth.RightMm[0] - truth.LeftMm[0]), -2.0, 2.0);
                }
                ReconFlags[] flags = extractor.FiberFlags();
                ReconFlags[] perfect = line.FiberFlags(frame.EncoderMm);
                SimulatedEdges row = line.StripEdges(new[] { frame.EncoderMm });
                for (int k = 0; k < Fibers; ++k)
                {
                    double x = FirstX + Pitch * k;
                    // Within 3 mm of an edge (a pitch and the edge's error)
                    // the partly covered fiber may be invalid rather than off.
                    if (Math.Abs(x - row.LeftMm[0]) <= 3 || Math.Abs(x - row.RightMm[0]) <= 3)
                        continue;
                    Assert.Equal(perfect[k] & ReconFlags.OffStrip, flags[k] & ReconFlags.OffStrip);
                }
                SaturationCount saturation = extractor.Saturation();
                Assert.True(saturation.Peaks > 0);
                Assert.Equal(0UL, saturation.Saturated);
            }
        }

        [Fact]
        public void SaturatedLinesAreMeasuredAndCounted()
        {
            // Lines at 1.5 x full scale blooming into their neighbours: >= 99 %
            // of the fibers between the edges valid (the goal; the C test
            // keeps 99.7 %), nearly every peak counted saturated.
            using var calib = Sensor();
            using var simOptions = new FlatlineOptions
            {
                SimSurround = SimSurround.RollerTable, SimStripWidth = 1500, SimLinePeak = 1.5,
                SimBlooming = 1, SimFrameSpacing = 37,
            };
            using var line = new SimulatedLine(calib, simOptions);
            line.AddDefect(DefectKind.CentreBuckle, 12, 1800);
            using var extractor = FieldExtractor(calib);
            SimulatedFrame frame = line.NextFrame();
            ProfileRow row = extractor.Process(frame);
            SaturationCount both = extractor.Saturation();
            Assert.True(both.Fraction >= 0.9, $"saturated fraction {both.Fraction}");
            Assert.Equal(both.Peaks, extractor.Saturation(0).Peaks + extractor.Saturation(1).Peaks);
            SimulatedEdges edges = line.StripEdges(new[] { frame.EncoderMm });
            int inside = 0, valid = 0;
            for (int k = 0; k < Fibers; ++k)
            {
                double x = FirstX + Pitch * k;
                if (x <= edges.LeftMm[0] + 3 || x >= edges.RightMm[0] - 3)
                    continue;
                ++inside;
                valid += row.Valid[k] ? 1 : 0;
            }
            Assert.True(valid >= 0.99 * inside, $"{valid} of {inside} fibers valid");
        }

        [Fact]
        public void OffStripFibersPassThroughTheReconstructor()
        {
            const int rows = 300, fibers = 4;
            var s = new double[rows];
            var height = new double[rows, fibers];
            var slope = new double[rows, fibers];
            var flags = new ReconFlags[rows, fibers];
            for (int r = 0; r < rows; ++r)
            {
                s[r] = 3.0 * r;
                for (int k = 0; k < fibers; ++k)
                {
                    height[r, k] = Math.Sin(s[r] / 900);
                    slope[r, k] = Math.Cos(s[r] / 900) / 900;
                }
                flags[r, 3] = ReconFlags.OffStrip;
                height[r, 3] = double.NaN;
            }
            ReconResult whole = Library.ReconstructFlagged(s, height, slope, flags);
            using var recon = new Reconstructor(fibers);
            recon.PushFlagged(s, height, slope, flags);
            recon.EndSheet();
            ReconResult streamed = recon.Pull();
            foreach (ReconResult result in new[] { whole, streamed })
                for (int r = 0; r < result.Rows; ++r)
                {
                    Assert.True(double.IsNaN(result.Z[r, 3]));
                    Assert.Equal((byte)ReconFlags.OffStrip, result.Flags[r, 3]);
                    for (int k = 0; k < 3; ++k)
                        Assert.False(double.IsNaN(result.Z[r, k]));
                }
            Assert.Throws<ArgumentNullException>(() => recon.PushFlagged(s, height, slope, null!));  // null on purpose: the check under test
            Assert.Throws<ArgumentException>(() => recon.PushFlagged(s, height, slope, new ReconFlags[rows, 3]));
        }

        [Fact]
        public void ZonesLieOnTheStrip()
        {
            // A 1200 mm strip 317 mm off centre with its edges: measured on
            // the strip, width and centre within a pitch of the truth.
            using var calib = Sensor();
            using var simOptions = new FlatlineOptions
            {
                SimSurround = SimSurround.Nothing, SimStripWidth = 1200, SimStripOffset = 317,
            };
            using var line = new SimulatedLine(calib, simOptions);
            line.AddDefect(DefectKind.WavyEdgeBoth, 10, 1000);
            SimulatedRows rows = line.NextRows(1200);
            SimulatedEdges edges = line.StripEdges(rows.EncoderMm);
            var flags = new byte[rows.Rows, Fibers];
            var z = new double[rows.Rows, Fibers];
            for (int r = 0; r < rows.Rows; ++r)
                for (int k = 0; k < Fibers; ++k)
                {
                    z[r, k] = rows.Valid[r, k] ? rows.Truth[r, k] : double.NaN;
                    flags[r, k] = rows.Valid[r, k] ? (byte)0 : (byte)ReconFlags.NoData;
                }
            using var flatness = new Flatness(calib);
            FlatnessResult result = flatness.EvaluateStrip(rows.S, z, flags, edges.LeftMm, edges.RightMm);
            Assert.True(result.Strip.OnStrip);
            Assert.True((result.Window.Flags & WindowFlags.OnStrip) != 0);
            Assert.InRange(result.Strip.WidthMm[0], 1200 - Pitch, 1200 + Pitch);
            Assert.InRange(result.Strip.CentreMm[0], 317 - Pitch, 317 + Pitch);
            Assert.Equal(ShapeClass.WavyEdgeBoth, result.Shape.Class);
            for (int k = 0; k < Fibers; ++k)
                Assert.Equal((k - (Fibers - 1) / 2.0) * Pitch, result.Strip.FiberStripX[k], 9);
            Assert.Contains(result.Zones.Flags, f => (f & ZoneFlags.OffStrip) != 0);
            Assert.Throws<ArgumentException>(
                () => flatness.EvaluateStrip(rows.S, z, flags, new double[3], edges.RightMm));
            var crossed = (double[])edges.LeftMm.Clone();
            crossed[5] = edges.RightMm[5] + 1;
            Assert.Throws<InvalidArgumentException>(
                () => flatness.EvaluateStrip(rows.S, z, flags, crossed, edges.RightMm));
        }

        [Fact]
        public void BadLasersAndEarlyCallsAreRefused()
        {
            using var calib = Sensor();
            using var extractor = FieldExtractor(calib);
            Assert.Throws<FlatlineStateException>(() => extractor.Strip());
            Assert.Throws<FlatlineStateException>(() => extractor.FiberFlags());
            Assert.Throws<FlatlineStateException>(() => extractor.Saturation());
            Assert.Throws<ArgumentOutOfRangeException>(() => extractor.Strip(3));
            Assert.Throws<ArgumentOutOfRangeException>(() => extractor.Saturation(-1));
            using var line = new SimulatedLine(calib);
            Assert.Throws<ArgumentOutOfRangeException>(() => line.StripEdges(new[] { 0.0 }, 5));
            Assert.Throws<InvalidArgumentException>(() => line.StripEdges(new[] { double.NaN }));
            Assert.Throws<InvalidArgumentException>(() => line.FiberFlags(double.PositiveInfinity));
        }
    }
}
