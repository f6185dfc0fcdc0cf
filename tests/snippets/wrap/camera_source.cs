// SPDX-License-Identifier: Apache-2.0
// bindings/csharp/README.md's camera source: the options and the extractor
// it names, and the row it writes.
using System;
using Flatline;

static class Snippet
{
    public static void Run()
    {
        using var options = new FlatlineOptions();
        using var calib = Calibration.Reference();
        using var extractor = new Extractor(calib);
        ProfileRow? row = null;
        // SNIPPET
        GC.KeepAlive(row);
    }
}
