// SPDX-License-Identifier: Apache-2.0
// A SCADA-style loop around the Flatline C# binding: camera frames from the
// simulated line go through the extractor (frame -> profile row) and the
// streaming reconstructor (rows -> flatness map), a cycle of frames at a
// time, the way a SCADA cycle collects frames and updates its tags.
//
// The line is libflatline's simulated sensor (SimulatedLine) seen through
// the reference sensor's calibration, reading out rows 960..1087 of the
// camera (both laser lines and +-50 mm of height): a strip with a centre
// buckle (12 mm over 1800 mm) and wavy edges (4 mm over 900 mm), a rigid
// heave of sigma 2.5 mm and a roll of 1 mrad per frame (the strip bouncing
// on the table), camera speckle and shot noise. Each sheet's accuracy
// against the simulator's ground truth is printed per zone across the width.
//
// Zone I-Units: each sheet's reconstructed rows also go to a Flatness
// object (one window per sheet, evaluated at the sheet's end), and the zone
// I-Unit profile is published per sheet the way a SCADA tag update would
// write it: one tag per zone across the width, plus the shape class, its
// confidence, bow and crossbow. The same metrics of the simulator's true
// heights are printed beside each tag, and a sheet is out of tolerance when
// a zone is more than ZoneTolerance I-Units off.
using System;
using System.Collections.Generic;
using Flatline;

internal static class Program
{
    private const int Fibers = 81;              // every 20 mm across 1600 mm
    private const double FiberPitch = 20.0;     // mm
    private const double FrameSpacing = 5.0;    // mm of travel per frame
    private const double SheetLength = 4000.0;  // mm
    private const int Sheets = 3;
    private const int FramesPerCycle = 50;      // one SCADA cycle
    private const int Zones = 5;                // accuracy columns across the width
    private const double ZoneWidth = 200.0;     // mm: I-Unit tags across the width

    private static int Main()
    {
        Console.WriteLine($"libflatline {Library.VersionString} through the Flatline NuGet package");
        using var calibration = Calibration.Reference(firstRow: 960, rows: 128,
                                                      firstXMm: -0.5 * FiberPitch * (Fibers - 1),
                                                      pitchMm: FiberPitch, fibers: Fibers);
        using var lineOptions = new FlatlineOptions
        {
            SimFrameSpacing = FrameSpacing, SimStripWidth = 1700, SimHeaveSigma = 2.5, SimTiltSigma = 1e-3, SimSeed = 2024,
        };
        using var line = new SimulatedLine(calibration, lineOptions);
        line.AddDefect(DefectKind.CentreBuckle, 12, 1800);
        line.AddDefect(DefectKind.WavyEdgeBoth, 4, 900);
        using var extractor = new Extractor(calibration);
        // The reconstructor takes the fibers and the laser spacing from the calibration.
        using var recon = new Reconstructor(calibration);
        // One flatness window per sheet: no automatic windows, Finish()
        // evaluates the sheet (800 rows, within the 4096-row capacity).
        using var flatOptions = new FlatlineOptions { FlatWindowLength = 0, FlatZoneWidth = ZoneWidth };
        using var flatness = new Flatness(calibration, flatOptions);
        using var flatnessOfTruth = new Flatness(calibration, flatOptions);
        Console.WriteLine($"camera {line.FrameWidth} x {line.FrameHeight} px {line.PixelFormat}, " +
                          $"{extractor.Fibers} fibers, knots every {recon.GetOption("knot_spacing")} mm");

        // The camera and row buffers are reused every frame (only the
        // accuracy bookkeeping below keeps a copy of each frame's truth).
        var pixels = new byte[line.FrameHeight, line.FrameWidth];
        var height = new double[extractor.Fibers];
        var slope = new double[extractor.Fibers];
        var valid = new bool[extractor.Fibers];
        var cycleS = new double[FramesPerCycle];
        var cycleHeight = new double[FramesPerCycle, extractor.Fibers];
        var cycleSlope = new double[FramesPerCycle, extractor.Fibers];
        var cycleValid = new bool[FramesPerCycle, extractor.Fibers];
        var truth = new double[extractor.Fibers];

        // Under the 2.5 mm heave and 1 mrad roll the fit averages the heights
        // of many frames per knot while the slopes, which rigid motion does
        // not touch, carry the shape: measured 0.06 .. 0.18 mm RMS per zone,
        // most of it a slowly drifting level and tilt of the whole strip
        // (which flatness in I-Units ignores). 0.25 mm RMS per sheet is the
        // alarm threshold.
        const double RmsTolerance = 0.25;
        // Zone I-Units against those of the true heights (the same metrics
        // of the simulator's ground truth on the same rows): measured 0.04 ..
        // 0.09 I-Units off on zones of up to 43 I-Units. 0.5 I-Units (about
        // 1% of the centre zone, below what an operator acts on) is the
        // alarm threshold.
        const double ZoneTolerance = 0.5;
        bool allWithin = true;
        int framesPerSheet = (int)(SheetLength / FrameSpacing);
        var truthByS = new Dictionary<double, double[]>();
        Console.WriteLine("sheet   rows   max error mm   rms error mm per zone (left .. right)");
        for (int sheet = 1; sheet <= Sheets; ++sheet)
        {
            var sumSquares = new double[Zones];
            var samples = new int[Zones];
            double worst = 0;
            int rows = 0;

            void Account(ReconResult block)
            {
                var truthBlock = new double[block.Rows, block.Fibers];
                for (int r = 0; r < block.Rows; ++r)
                {
                    double[] expected = truthByS[block.S[r]];
                    truthByS.Remove(block.S[r]);
                    for (int k = 0; k < block.Fibers; ++k)
                    {
                        truthBlock[r, k] = expected[k];
                        double error = block.Z[r, k] - expected[k];
                        int zone = k * Zones / block.Fibers;
                        sumSquares[zone] += error * error;
                        ++samples[zone];
                        worst = Math.Max(worst, Math.Abs(error));
                    }
                }
                rows += block.Rows;
                // The sheet's rows so far go to the flatness metrics (with
                // FlatWindowLength 0 a push takes every row and never
                // evaluates on its own).
                if (block.Rows > 0)
                {
                    flatness.Push(block.S, block.Z, block.Flags);
                    flatnessOfTruth.Push(block.S, truthBlock);
                }
            }

            for (int first = 0; first < framesPerSheet; first += FramesPerCycle)
            {
                int count = Math.Min(FramesPerCycle, framesPerSheet - first);
                for (int f = 0; f < count; ++f)
                {
                    double encoder = line.NextFrame(pixels, truth);
                    double s = extractor.Process(pixels, encoder, height, slope, valid);
                    truthByS[s] = (double[])truth.Clone();
                    cycleS[f] = s;
                    for (int k = 0; k < extractor.Fibers; ++k)
                    {
                        cycleHeight[f, k] = height[k];
                        cycleSlope[f, k] = slope[k];
                        cycleValid[f, k] = valid[k];
                    }
                }
                if (count == FramesPerCycle)
                    recon.Push(cycleS, cycleHeight, cycleSlope, cycleValid);
                else
                    for (int f = 0; f < count; ++f)
                        recon.Push(cycleS[f], Row(cycleHeight, f), Row(cycleSlope, f), Row(cycleValid, f));
                Account(recon.Pull());   // the rows this cycle finished
            }
            recon.EndSheet();            // the sheet's tail, with carry-over into the next
            Account(recon.Pull());

            var zoneRms = new string[Zones];
            double sheetSquares = 0;
            int sheetSamples = 0;
            for (int z = 0; z < Zones; ++z)
            {
                zoneRms[z] = $"{Math.Sqrt(sumSquares[z] / samples[z]),6:F3}";
                sheetSquares += sumSquares[z];
                sheetSamples += samples[z];
            }
            double rms = Math.Sqrt(sheetSquares / sheetSamples);
            bool within = rms < RmsTolerance && rows == framesPerSheet;
            // The sheet's flatness, published as SCADA tags.
            flatness.Finish();
            flatnessOfTruth.Finish();
            var measured = flatness.Result();
            var trueFlatness = flatnessOfTruth.Result();
            var report = new System.Text.StringBuilder();
            var shape = measured.Shape;
            report.AppendLine($"sheet {sheet}: s {measured.Window.SFirstMm:F0} .. {measured.Window.SLastMm:F0} mm, " +
                              $"{measured.Window.Rows} rows");
            report.AppendLine($"  Line1.Flatness.Shape      = \"{shape.Name}\" ({shape.Confidence:P0}; " +
                              $"true \"{trueFlatness.Shape.Name}\")");
            report.AppendLine($"  Line1.Flatness.BowMm      = {shape.BowMm,7:F2}   (true {trueFlatness.Shape.BowMm:F2})");
            report.AppendLine($"  Line1.Flatness.CrossbowMm = {shape.CrossbowMm,7:F2}   (true {trueFlatness.Shape.CrossbowMm:F2})");
            double worstZone = 0;
            for (int j = 0; j < measured.Zones.Count; ++j)
            {
                double iUnits = measured.Zones.IUnits[j], expected = trueFlatness.Zones.IUnits[j];
                worstZone = Math.Max(worstZone, Math.Abs(iUnits - expected));
                report.AppendLine($"  Line1.Flatness.Zone{j + 1:D2}.IUnits = {iUnits,6:F2}   " +
                                  $"(x {measured.Zones.CentreX[j],6:F0} mm, true {expected,6:F2})");
            }
            within &= worstZone < ZoneTolerance;
            allWithin &= within;
            report.Append($"  zone I-Units within {worstZone:F2} of the truth");
            Console.WriteLine($"{sheet,5} {rows,6} {worst,14:F3}   {string.Join(" ", zoneRms)}" +
                              $"{(within ? "" : "   OUT OF TOLERANCE")}");
            Console.WriteLine(report.ToString());   // the sheet's tag update
        }
        Console.WriteLine(allWithin ? "all sheets within tolerance" : "some sheets out of tolerance");
        return allWithin ? 0 : 1;
    }

    private static T[] Row<T>(T[,] block, int row)
    {
        var values = new T[block.GetLength(1)];
        for (int k = 0; k < values.Length; ++k)
            values[k] = block[row, k];
        return values;
    }
}
