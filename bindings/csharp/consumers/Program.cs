// SPDX-License-Identifier: Apache-2.0
// A SCADA add-in's first call into the Flatline package, written in the C#
// that .NET Framework 4.8 projects compile (7.3): reconstruct a sampled
// sine from its two-laser heights and slopes and print the worst error.
// Built for net48 (the package's netstandard2.0 assembly) and net8.0 (its
// net8.0 assembly) by ctest's csharp.frameworks.
using System;
using Flatline;

internal static class Program
{
    private static int Main()
    {
        const int rows = 300, fibers = 4;
        const double period = 1800.0, amplitude = 5.0, half = 50.0;
        var s = new double[rows];
        var height = new double[rows, fibers];
        var slope = new double[rows, fibers];
        for (int r = 0; r < rows; ++r)
        {
            s[r] = 3.0 * r;
            for (int k = 0; k < fibers; ++k)
            {
                double a = amplitude * Math.Sin(2 * Math.PI * (s[r] - half) / period);
                double b = amplitude * Math.Sin(2 * Math.PI * (s[r] + half) / period);
                height[r, k] = 0.5 * (a + b);
                slope[r, k] = (b - a) / (2 * half);
            }
        }
        ReconResult result = Library.Reconstruct(s, height, slope);
        double worst = 0;
        for (int r = 0; r < rows; ++r)
            for (int k = 0; k < fibers; ++k)
                worst = Math.Max(worst, Math.Abs(result.Z[r, k] - amplitude * Math.Sin(2 * Math.PI * s[r] / period)));
        Console.WriteLine("libflatline " + Library.VersionString + ": " + result.Rows + " rows, max error " +
                          worst.ToString("G3", System.Globalization.CultureInfo.InvariantCulture) + " mm");
        // A noise-free sine sampled every 3 mm reconstructs within 1 um (the
        // C consumer test measures the same case).
        return worst < 1e-3 ? 0 : 1;
    }
}
