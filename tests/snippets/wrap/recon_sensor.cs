// SPDX-License-Identifier: Apache-2.0
// bindings/csharp/README.md's first block: profile rows of a flat strip with
// a small wave (s [rows], height/slope [rows, 9]) and the sensor file it
// loads (the reference sensor).
using System;
using Flatline;

static class Snippet
{
    public static void Run()
    {
        const int rows = 400;
        double[] s = new double[rows];
        double[,] height = new double[rows, 9], slope = new double[rows, 9];
        for (int i = 0; i < rows; ++i)
        {
            s[i] = 5.0 * i;
            for (int k = 0; k < 9; ++k)
            {
                height[i, k] = 0.5 * Math.Sin(2 * Math.PI * s[i] / 1000.0);
                slope[i, k] = 0.5 * 2 * Math.PI / 1000.0 * Math.Cos(2 * Math.PI * s[i] / 1000.0);
            }
        }
        using (var reference = Calibration.Reference())
            reference.Save("sensor.json");
        // SNIPPET
    }
}
