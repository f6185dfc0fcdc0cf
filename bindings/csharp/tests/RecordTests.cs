// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.IO;
using System.Linq;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>The quality record from C#: a recording written and read back
    /// (each laser within half a quantum of what was pushed), a file never
    /// overwritten, coil identities checked by the library, the archive's
    /// life cycle.</summary>
    public class RecordTests : IDisposable
    {
        private readonly string dir = Path.Combine(Path.GetTempPath(), "flt_cs_record_" + Guid.NewGuid().ToString("N"));

        public RecordTests() => Directory.CreateDirectory(dir);

        public void Dispose()
        {
            try { Directory.Delete(dir, true); } catch (IOException) { }
        }

        private static Calibration Calib() =>
            Calibration.Reference(firstRow: 0, rows: 2048, firstXMm: -500, pitchMm: 30, fibers: 16);

        [Fact]
        public void RowsComeBackWithinHalfAQuantum()
        {
            using var calib = Calib();
            string path = Path.Combine(dir, "r.flrec");
            const int rows = 300;
            var rng = new Random(5);
            var h = new double[rows][];
            var s = new double[rows][];
            using (var rec = new Recorder(path, calib))
            {
                rec.SetCoil(new CoilInfo("4711", grade: "S355MC", thicknessMm: 4,
                                         extras: new Dictionary<string, string> { ["line"] = "Süd" }));
                for (int r = 0; r < rows; ++r)
                {
                    h[r] = new double[16];
                    s[r] = new double[16];
                    for (int k = 0; k < 16; ++k)
                    {
                        h[r][k] = Math.Sin(0.01 * r + k) + 0.05 * rng.NextDouble();
                        s[r][k] = 0.001 * rng.NextDouble();
                    }
                    if (r == 100)
                        rec.Cut(100.0);
                    rec.PushRow(r, h[r], s[r]);
                }
                rec.Sync();
                Assert.Equal((ulong)rows, rec.Counters()["rows_stored"]);
                Assert.Equal(0UL, rec.Counters()["rows_lost"]);
            }
            Assert.Throws<FlatlineIOException>(() => new Recorder(path, calib));
            using var rd = new Recording(path);
            Assert.Equal(rows, rd.Rows);
            Assert.Equal(16, rd.Fibers);
            rd.Verify();
            var got = rd.ReadRows();
            double q = rd.QuantumMm, spacing = 100.0;
            Assert.Equal(1.0 / 256, q);
            double worst = 0;
            for (int r = 0; r < rows; ++r)
            {
                Assert.Equal((double)r, got.EncoderMm[r]);
                for (int k = 0; k < 16; ++k)
                {
                    double pushed = h[r][k] - s[r][k] * spacing / 2;
                    double stored = got.Height[r, k] - got.Slope[r, k] * spacing / 2;
                    worst = Math.Max(worst, Math.Abs(pushed - stored));
                }
            }
            // Rounding to the quantum: half a quantum (and the arithmetic's ulps).
            Assert.InRange(worst, 0.0, q / 2 + 1e-9);
            using var back = rd.Calibration();
            Assert.Equal(16, back.FiberGrid.Count);

            // The same file without libflatline (examples/read_recording_cs):
            // bit for bit.
            using var file = new FlatlineRecordingReader.RecordingFile(path);
            long row = 0;
            foreach (var block in file.Blocks())
                for (int i = 0; i < block.Rows; ++i, ++row)
                {
                    Assert.Equal(got.EncoderMm[row], block.EncoderMm[i]);
                    for (int k = 0; k < 16; ++k)
                    {
                        Assert.Equal(got.Height[row, k], block.Height[i, k]);
                        Assert.Equal(got.Slope[row, k], block.Slope[i, k]);
                    }
                }
            Assert.Equal(rows, row);
        }

        [Fact]
        public async System.Threading.Tasks.Task ARecordedLineReplaysBitForBitAndIsArchived()
        {
            // A wavy strip of 51 fibers, rows every 3 mm over 9 m, cut every
            // 1500 mm, measured by 2 workers with a recorder and an archive.
            using var calib = Calibration.Reference(firstRow: 900, rows: 240, firstXMm: -750, pitchMm: 30, fibers: 51);
            string path = Path.Combine(dir, "line.flrec"), archivePath = Path.Combine(dir, "line.sqlite");
            var live = new List<Flatline.Sheet>();
            using (var options = new FlatlineOptions { GaugeWorkers = 2, GaugeKeepMaps = 1, GaugeFrameSpacing = 2.0 })
            using (var gauge = new Gauge(calib, options))
            using (var rec = new Recorder(path, calib))
            using (var archive = new Archive(archivePath, "C# line"))
            {
                gauge.AttachRecorder(rec);
                gauge.AttachArchive(archive);
                gauge.SetCoil(new CoilInfo("C-42", grade: "DC04", thicknessMm: 1.5));
                for (int c = 1; c < 6; ++c)
                    gauge.Cut(1500.0 * c);
                var h = new double[51];
                var sl = new double[51];
                var rng = new Random(11);
                for (int r = 0; r < 3000; ++r)
                {
                    double s = 3.0 * r;
                    for (int k = 0; k < 51; ++k)
                    {
                        double behind = 4 * Math.Sin(2 * Math.PI * (s - 50) / 1300) * Math.Cos(k * 0.1),
                               ahead = 4 * Math.Sin(2 * Math.PI * (s + 50) / 1300) * Math.Cos(k * 0.1);
                        h[k] = 0.5 * (behind + ahead) + 0.02 * (rng.NextDouble() - 0.5);
                        sl[k] = (ahead - behind) / 100.0;
                    }
                    if (r == 1000)
                        gauge.Note("leveler", "roll 2 -0.1 mm");
                    gauge.PushRow(s, h, sl);
                    for (Flatline.Sheet? sheet; (sheet = gauge.NextSheet()) != null;)
                        live.Add(sheet);
                }
                gauge.Flush();
                for (Flatline.Sheet? sheet; (sheet = gauge.NextSheet()) != null;)
                    live.Add(sheet);
                gauge.AttachRecorder(null);
                gauge.AttachArchive(null);
                archive.Flush();
                Assert.Equal((ulong)live.Count, archive.Counters()["stored"]);
            }
            Assert.Equal(6, live.Count);
            Assert.All(live, s => Assert.Equal("C-42", s.CoilInfo!.CoilId));
            Assert.Single(live.SelectMany(s => s.Notes));

            var again = new List<Flatline.Sheet>();
            using (var rd = new Recording(path))
            using (var replayCalib = rd.Calibration())
            using (var replayOptions = rd.Options())
            using (var gauge = new Gauge(replayCalib, replayOptions))
            using (var source = FrameSource.OpenRecording(path))
            {
                await foreach (var sheet in gauge.RunAsync(source, TestContext.Current.CancellationToken))
                    again.Add(sheet);
            }
            Assert.Equal(live.Count, again.Count);
            for (int i = 0; i < live.Count; ++i)
            {
                // Bit for bit (tolerance 0: the same doubles through the same code).
                Assert.Equal(live[i].Z, again[i].Z);
                Assert.Equal(live[i].ZoneIUnits, again[i].ZoneIUnits);
                Assert.Equal(live[i].MaxIUnits, again[i].MaxIUnits);
                Assert.Equal(live[i].CoilInfo, again[i].CoilInfo);
                Assert.Equal(live[i].Notes.Count, again[i].Notes.Count);
            }
        }

        [Fact]
        public void CoilIdentityIsCheckedByTheLibrary()
        {
            using var calib = Calib();
            using var rec = new Recorder(Path.Combine(dir, "c.flrec"), calib);
            Assert.Throws<InvalidArgumentException>(() => rec.SetCoil(new CoilInfo("")));
            Assert.Throws<InvalidArgumentException>(() => rec.SetCoil(new CoilInfo("a", grade: "x\ny")));
            Assert.Throws<InvalidArgumentException>(() => rec.SetCoil(new CoilInfo("a", thicknessMm: double.NaN)));
            rec.SetCoil(new CoilInfo("ok"));
            Assert.Equal(new CoilInfo("a", grade: "g"), new CoilInfo("a", grade: "g"));
        }

        [Fact]
        public void ArchiveOpensCountsAndCloses()
        {
            string path = Path.Combine(dir, "a.sqlite");
            using (var ar = new Archive(path, "CTL 2"))
            {
                Assert.Equal("sqlite", ar.Backend);
                ar.Flush(1000);
                Assert.Equal(0UL, ar.Prune());
                Assert.Equal(0UL, ar.Counters()["stored"]);
            }
            Assert.True(File.Exists(path));
            Assert.Throws<InvalidArgumentException>(() => new Archive(path, "bad\nline"));
        }
    }
}
