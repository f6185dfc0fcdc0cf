// SPDX-License-Identifier: Apache-2.0
// bindings/csharp/README.md's gauge: the reference sensor, 20 frames of the
// simulated line, and Publish.
using System;
using System.Collections.Generic;
using Flatline;

static class Snippet
{
    static void Publish(Sheet sheet) => Console.WriteLine($"  sheet {sheet.Id}");

    public static void Run()
    {
        using var calibration = Calibration.Reference();
        var frames = new List<SimulatedFrame>();
        using (var line = new SimulatedLine(calibration))
            for (int i = 0; i < 20; ++i)
                frames.Add(line.NextFrame());
        // SNIPPET
    }
}
