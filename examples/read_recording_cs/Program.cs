// SPDX-License-Identifier: Apache-2.0
// Prints what a libflatline recording holds, read without libflatline.
//   dotnet run -- line.flrec
using System;
using FlatlineRecordingReader;

if (args.Length != 1)
{
    Console.Error.WriteLine("usage: ReadRecording <recording>");
    return 2;
}
using var file = new RecordingFile(args[0]);
long rows = 0;
foreach (var block in file.Blocks())
    rows += block.Rows;
Console.WriteLine($"{args[0]}: {rows} rows x {file.Fibers} fibers, quantum {file.QuantumMm} mm, " +
                  $"library {file.Meta["library"]}; every block's CRC-32 checked");
return 0;
