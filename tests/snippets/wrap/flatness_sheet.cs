// SPDX-License-Identifier: Apache-2.0
// bindings/csharp/README.md's flatness: a sheet of the reference sensor's
// 1001 fibers, 9 m long (windows of the default 5 m every 1 m), a 2 mm
// wave along (s, z, flags), and Publish.
using System;
using Flatline;

static class Snippet
{
    static int published;

    static void Publish(double[] zoneIUnits)
    {
        if (zoneIUnits.Length == 0)
            throw new InvalidOperationException("a window without zones");
        ++published;
    }

    public static void Run()
    {
        using var calib = Calibration.Reference();
        const int rows = 3000, fibers = 1001;
        double[] s = new double[rows];
        double[,] z = new double[rows, fibers];
        byte[,] flags = new byte[rows, fibers];
        for (int i = 0; i < rows; ++i)
        {
            s[i] = 3.0 * i;
            for (int k = 0; k < fibers; ++k)
                z[i, k] = 2.0 * Math.Sin(2 * Math.PI * s[i] / 1000.0);
        }
        // SNIPPET
        Console.WriteLine($"  {published} windows published");
        if (published == 0)
            throw new InvalidOperationException("the streaming loop published no window");
    }
}
