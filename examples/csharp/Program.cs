// A SCADA-style loop around the Flatline C# binding.
//
// The line is simulated here, in C#: a strip whose height is
//     z(s, x) = 12 sin(2 pi s / 1800) cos(2 pi x / 1500)   (mm)
// passes under the dual-line-laser gauge. Every camera frame gives, per
// fiber, what the two lasers 100 mm apart measure (mean height and secant
// slope), plus a rigid vibration of sigma 2.5 mm that moves the whole strip
// (every fiber of the frame, both lasers) up and down. The frames are
// streamed through Reconstructor in blocks, the way a SCADA cycle collects
// frames and updates its tags, and each sheet's accuracy is printed.
//
// Zone I-Units: the per-sheet zone I-Unit profile comes with libflatline's
// flatness component, which is not written yet. When it lands, the loop
// below feeds each pulled block to it and prints the I-Unit tags per zone
// in place of the accuracy table.
using System;
using System.Collections.Generic;
using Flatline;

internal static class Program
{
    private const int Fibers = 9;               // across a 1600 mm strip
    private const double FiberPitch = 200.0;    // mm, x = -800 ... 800
    private const double FrameSpacing = 2.0;    // mm of travel per frame
    private const double SheetLength = 6000.0;  // mm
    private const int Sheets = 3;
    private const int FramesPerCycle = 50;      // one SCADA cycle
    private const double VibrationSigma = 2.5;  // mm, common to all fibers
    private const double LaserSpacing = 100.0;  // mm

    private static double Surface(double s, double x) =>
        12.0 * Math.Sin(2 * Math.PI * s / 1800.0) * Math.Cos(2 * Math.PI * x / 1500.0);

    private static double Gaussian(Random random)
    {
        double u1 = 1.0 - random.NextDouble(), u2 = random.NextDouble();
        return Math.Sqrt(-2.0 * Math.Log(u1)) * Math.Cos(2 * Math.PI * u2);
    }

    private static int Main()
    {
        Console.WriteLine($"libflatline {Library.VersionString} through the Flatline NuGet package");
        var random = new Random(2024);
        using var options = new FlatlineOptions { LaserSpacing = LaserSpacing, HeightSigma = VibrationSigma };
        using var recon = new Reconstructor(Fibers, options);
        Console.WriteLine($"reconstructor: {recon.Fibers} fibers, knots every {recon.GetOption("knot_spacing")} mm, " +
                          $"lag {recon.GetOption("lag_knots")} knots");

        int framesPerSheet = (int)(SheetLength / FrameSpacing);
        // Under sigma 2.5 mm of vibration per frame the fit averages the
        // heights of many frames per knot (and slopes, which the bouncing
        // does not touch, carry the shape): measured here 0.08 mm RMS per
        // sheet. 0.25 mm RMS is the alarm threshold, three times that.
        const double RmsTolerance = 0.25;
        bool allWithin = true;
        double s = 0.0;
        Console.WriteLine("sheet   rows   rms error mm   max error mm   flagged");
        for (int sheet = 1; sheet <= Sheets; ++sheet)
        {
            var truth = new Dictionary<double, double[]>();
            double sumSquares = 0, worst = 0;
            int samples = 0, flagged = 0, rows = 0;

            void Account(ReconResult block)
            {
                for (int r = 0; r < block.Rows; ++r)
                {
                    double[] expected = truth[block.S[r]];
                    truth.Remove(block.S[r]);
                    for (int k = 0; k < Fibers; ++k)
                    {
                        double error = block.Z[r, k] - expected[k];
                        sumSquares += error * error;
                        worst = Math.Max(worst, Math.Abs(error));
                        ++samples;
                        if (block.Flags[r, k] != 0)
                            ++flagged;
                    }
                }
                rows += block.Rows;
            }

            for (int first = 0; first < framesPerSheet; first += FramesPerCycle)
            {
                int count = Math.Min(FramesPerCycle, framesPerSheet - first);
                var frameS = new double[count];
                var height = new double[count, Fibers];   // [frame, fiber], row-major
                var slope = new double[count, Fibers];
                for (int f = 0; f < count; ++f)
                {
                    s += FrameSpacing;
                    frameS[f] = s;
                    double bounce = VibrationSigma * Gaussian(random);
                    var expected = new double[Fibers];
                    for (int k = 0; k < Fibers; ++k)
                    {
                        double x = (k - (Fibers - 1) / 2.0) * FiberPitch;
                        double rear = Surface(s - LaserSpacing / 2, x), front = Surface(s + LaserSpacing / 2, x);
                        height[f, k] = (rear + front) / 2 + bounce;
                        slope[f, k] = (front - rear) / LaserSpacing;
                        expected[k] = Surface(s, x);
                    }
                    truth[s] = expected;
                }
                recon.Push(frameS, height, slope);
                Account(recon.Pull());   // the rows this cycle finished
            }
            recon.EndSheet();            // the sheet's tail, with carry-over into the next
            Account(recon.Pull());

            double rms = Math.Sqrt(sumSquares / samples);
            bool within = rms < RmsTolerance && rows == framesPerSheet;
            allWithin &= within;
            Console.WriteLine($"{sheet,5} {rows,6} {rms,14:F3} {worst,14:F3} {flagged,9}{(within ? "" : "   OUT OF TOLERANCE")}");
        }
        Console.WriteLine(allWithin ? "all sheets within tolerance" : "some sheets out of tolerance");
        Console.WriteLine("(zone I-Units: printed here once libflatline's flatness component lands)");
        return allWithin ? 0 : 1;
    }
}
