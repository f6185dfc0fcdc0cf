// SPDX-License-Identifier: Apache-2.0
// A SCADA-style program around the Flatline C# binding: camera frames from
// the simulated line and the shear's cuts go into one Gauge, and each
// measured sheet comes back as an event, published the way a SCADA tag
// update writes it.
//
// The line is libflatline's simulated sensor (SimulatedLine) seen through
// the reference sensor's calibration, reading out rows 960..1087 of the
// camera (both laser lines and +-50 mm of height): a strip with a centre
// buckle (12 mm over 1800 mm) and wavy edges (4 mm over 900 mm), a rigid
// heave of sigma 2.5 mm and a roll of 1 mrad per frame (the strip bouncing
// on the table), camera speckle and shot noise, a frame every 5 mm and a
// cut every 4 m. The gauge's workers extract each frame's profile, its
// reconstructor streams the strip's shape on across the cuts, and each
// sheet arrives with its shape class, bow, crossbow and zone I-Units (and
// its height map, kept here to check it). Each sheet's accuracy against the
// simulator's ground truth is printed per zone across the width, and its
// zone I-Units beside those of the true heights.
//
// `--dump FILE` also writes every sheet's reconstructed rows (s, then z per
// fiber, round-trip decimal text) to FILE: ctest runs the example on Linux
// and as a self-contained win-x64 program under wine and compares the two.
#nullable enable
using System;
using System.Collections.Concurrent;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using System.Threading;
using Flatline;

internal static class Program
{
    private const int Fibers = 81;              // every 20 mm across 1600 mm
    private const double FiberPitch = 20.0;     // mm
    private const double FrameSpacing = 5.0;    // mm of travel per frame
    private const double SheetLength = 4000.0;  // mm between the shear's cuts
    private const int Sheets = 3;
    private const int Zones = 5;                // accuracy columns across the width
    private const double ZoneWidth = 200.0;     // mm: I-Unit tags across the width

    private static int Main(string[] args)
    {
        StreamWriter? dump = null;
        if (args.Length == 2 && args[0] == "--dump")
            dump = new StreamWriter(args[1]);
        else if (args.Length != 0)
        {
            Console.Error.WriteLine("usage: FlatlineExample [--dump FILE]");
            return 2;
        }
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

        // ---- the gauge: what a vendor writes --------------------------------
        // rigid_motion takes the strip's bounce out of its shape; the gauge
        // keeps each sheet's height map (here: to check it against the
        // truth); rendered frames may wait for the gauge (a camera's cannot:
        // set GaugeOverflow = GaugeOverflow.Drop and watch GaugeCounter.Dropped).
        using var options = new FlatlineOptions
        {
            RigidMotion = true, FlatZoneWidth = ZoneWidth, GaugeFrameSpacing = 0.8 * FrameSpacing,
            GaugeOverflow = GaugeOverflow.Wait, GaugeKeepMaps = 1,
        };
        using var gauge = new Gauge(calibration, options);
        var finished = new BlockingCollection<Sheet>();
        gauge.SheetFinished += (sender, e) => finished.Add(e.Sheet);  // on a gauge thread
        for (int cut = 1; cut < Sheets; ++cut)
            gauge.Cut(cut * SheetLength);

        // The truth of every frame, by its row position, and the same
        // flatness metrics of the true heights, to check the tags.
        var truthByRow = new Dictionary<long, double[]>();
        using var flatOptions = new FlatlineOptions { FlatWindowLength = 0, FlatZoneWidth = ZoneWidth };
        using var flatnessOfTruth = new Flatness(calibration, flatOptions);

        // Under the 2.5 mm heave and 1 mrad roll the fit averages the heights
        // of many frames per knot while the slopes, which rigid motion does
        // not touch, carry the shape: the error is mostly a slowly drifting
        // level and tilt of the whole strip (which flatness in I-Units
        // ignores). 0.25 mm RMS per sheet is the alarm threshold.
        const double RmsTolerance = 0.25;
        // Zone I-Units against those of the true heights on the same rows.
        // 0.5 I-Units (about 1 % of the centre zone, below what an operator
        // acts on) is the alarm threshold.
        const double ZoneTolerance = 0.5;
        bool allWithin = true;
        int published = 0;
        Console.WriteLine("sheet   rows   max error mm   rms error mm per zone (left .. right)");

        void Publish(Sheet sheet)
        {
            var sumSquares = new double[Zones];
            var samples = new int[Zones];
            double worst = 0;
            var truth = new double[sheet.Rows, Fibers];
            if (dump != null)
                for (int r = 0; r < sheet.Rows; ++r)
                {
                    var text = new System.Text.StringBuilder(sheet.S![r].ToString("R", CultureInfo.InvariantCulture));
                    for (int k = 0; k < Fibers; ++k)
                        text.Append(' ').Append(sheet.Z![r, k].ToString("R", CultureInfo.InvariantCulture));
                    dump.WriteLine(text.ToString());
                }
            for (int r = 0; r < sheet.Rows; ++r)
            {
                double[] expected = truthByRow[(long)Math.Round(sheet.S![r] / FrameSpacing)];
                for (int k = 0; k < Fibers; ++k)
                {
                    truth[r, k] = expected[k];
                    double error = sheet.Z![r, k] - expected[k];
                    int zone = k * Zones / Fibers;
                    sumSquares[zone] += error * error;
                    ++samples[zone];
                    worst = Math.Max(worst, Math.Abs(error));
                }
            }
            var zoneRms = new string[Zones];
            double squares = 0;
            int count = 0;
            for (int z = 0; z < Zones; ++z)
            {
                zoneRms[z] = $"{Math.Sqrt(sumSquares[z] / samples[z]),6:F3}";
                squares += sumSquares[z];
                count += samples[z];
            }
            bool within = Math.Sqrt(squares / count) < RmsTolerance;
            var trueFlatness = flatnessOfTruth.Evaluate(sheet.S!, truth);
            var report = new System.Text.StringBuilder();
            report.AppendLine($"sheet {sheet.Id}: s {sheet.SStartMm:F0} .. {sheet.SEndMm:F0} mm, {sheet.Rows} rows, " +
                              $"{sheet.Frames} frames, {sheet.Dropped} dropped");
            report.AppendLine($"  Line1.Flatness.Shape      = \"{sheet.ShapeName}\" ({sheet.Confidence:P0}; " +
                              $"true \"{trueFlatness.Shape.Name}\")");
            report.AppendLine($"  Line1.Flatness.BowMm      = {sheet.BowMm,7:F2}   (true {trueFlatness.Shape.BowMm:F2})");
            report.AppendLine($"  Line1.Flatness.CrossbowMm = {sheet.CrossbowMm,7:F2}   (true {trueFlatness.Shape.CrossbowMm:F2})");
            report.AppendLine($"  Line1.Flatness.WaveMm     = {sheet.WaveHeightMm,7:F2}   " +
                              $"(over {sheet.WavePeriodMm:F0} mm at x {sheet.WaveXMm:F0} mm)");
            double worstZone = 0;
            for (int j = 0; j < sheet.ZoneIUnits.Length; ++j)
            {
                double iUnits = sheet.ZoneIUnits[j], expected = trueFlatness.Zones.IUnits[j];
                worstZone = Math.Max(worstZone, Math.Abs(iUnits - expected));
                report.AppendLine($"  Line1.Flatness.Zone{j + 1:D2}.IUnits = {iUnits,6:F2}   " +
                                  $"(x {sheet.ZoneCentreX[j],6:F0} mm, true {expected,6:F2})");
            }
            within &= worstZone < ZoneTolerance;
            allWithin &= within;
            report.Append($"  zone I-Units within {worstZone:F2} of the truth");
            Console.WriteLine($"{sheet.Id,5} {sheet.Rows,6} {worst,14:F3}   {string.Join(" ", zoneRms)}" +
                              $"{(within ? "" : "   OUT OF TOLERANCE")}");
            Console.WriteLine(report.ToString());   // the sheet's tag update
            ++published;
        }

        // The line: one frame every 5 mm; each finished sheet is published
        // on this thread as it comes.
        var pixels = new byte[line.FrameHeight, line.FrameWidth];
        var frameTruth = new double[Fibers];
        int frames = (int)(Sheets * SheetLength / FrameSpacing);
        for (int f = 0; f < frames; ++f)
        {
            double encoder = line.NextFrame(pixels, frameTruth);
            truthByRow[(long)Math.Round(encoder / FrameSpacing)] = (double[])frameTruth.Clone();
            gauge.Push(pixels, encoder);
            while (finished.TryTake(out Sheet? sheet))
                Publish(sheet);
        }
        gauge.Flush();   // the end of the strip: its last sheet
        while (finished.TryTake(out Sheet? sheet, TimeSpan.FromSeconds(1)))
            Publish(sheet);
        Console.WriteLine($"{published} sheets; the gauge counted {gauge.Count(GaugeCounter.Frames)} frames, " +
                          $"{gauge.Count(GaugeCounter.Dropped)} dropped, reconstructor rows held " +
                          $"{gauge.GetOption("row_capacity")}");
        allWithin &= published == Sheets;
        dump?.Dispose();
        Console.WriteLine(allWithin ? "all sheets within tolerance" : "some sheets out of tolerance");
        return allWithin ? 0 : 1;
    }
}
