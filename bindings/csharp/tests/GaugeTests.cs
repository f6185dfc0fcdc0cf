// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.Linq;
using System.Runtime.CompilerServices;
using System.Threading;
using System.Threading.Tasks;
using Xunit;

namespace Flatline.Tests
{
    public class GaugeTests
    {
        private const int Fibers = 51;          // across 1500 mm
        private const double Pitch = 30.0;      // mm
        private const double Step = 3.0;        // mm between rows
        private readonly ITestOutputHelper output;
        public GaugeTests(ITestOutputHelper output) => this.output = output;

        private static Calibration Sensor() =>
            Calibration.Reference(firstRow: 900, rows: 240, firstXMm: -750, pitchMm: Pitch, fibers: Fibers);

        // The reference's sheet, 12 sin(2 pi s / 1800) cos(2 pi x / 1500),
        // as two lasers 100 mm apart measure it, noise-free.
        private static double Z(double s, int k) =>
            12.0 * Math.Sin(2 * Math.PI * s / 1800.0) * Math.Cos(2 * Math.PI * (-750 + Pitch * k) / 1500.0);

        private static void Row(int r, double[] height, double[] slope)
        {
            double s = Step * r;
            for (int k = 0; k < Fibers; ++k)
            {
                double behind = Z(s - 50, k), ahead = Z(s + 50, k);
                height[k] = 0.5 * (behind + ahead);
                slope[k] = (ahead - behind) / 100.0;
            }
        }

        private static void PushRows(Gauge gauge, int first, int end)
        {
            var height = new double[Fibers];
            var slope = new double[Fibers];
            for (int r = first; r < end; ++r)
            {
                Row(r, height, slope);
                gauge.PushRow(Step * r, height, slope);
            }
        }

        private static FlatlineOptions Options(int workers = 2) => new FlatlineOptions
        {
            GaugeWorkers = workers, GaugeOverflow = GaugeOverflow.Wait, GaugeKeepMaps = 1, GaugeSheetSlots = 16,
            GaugeFrameSpacing = 2.0,
        };

        private static List<Flatline.Sheet> Drain(Gauge gauge)
        {
            var sheets = new List<Flatline.Sheet>();
            for (Flatline.Sheet? sheet; (sheet = gauge.NextSheet()) != null;)
                sheets.Add(sheet);
            return sheets;
        }

        [Fact]
        public void RowsAndCutsGiveSheetsThatEndAtTheirCuts()
        {
            using var calibration = Sensor();
            using var options = Options();
            using var gauge = new Gauge(calibration, options);
            gauge.Cut(3000);
            gauge.Cut(6000);
            PushRows(gauge, 0, 3000);  // 9 m
            gauge.Flush();
            var sheets = Drain(gauge);
            Assert.Equal(new long[] { 1, 2, 3 }, sheets.Select(s => s.Id));
            Assert.Equal(SheetFlags.Head, sheets[0].Flags);
            Assert.True(sheets[2].Flags.HasFlag(SheetFlags.Flushed));
            Assert.Equal(3000.0, sheets[0].SEndMm);
            Assert.Equal(3000.0, sheets[1].SStartMm);
            Assert.Equal(3000, sheets.Sum(s => s.Rows));
            Assert.True(sheets[0].S![sheets[0].Rows - 1] < 3000 && sheets[1].S![0] >= 3000);
            // Noise-free rows: within 1 um of the truth (the reconstructor's
            // own figure on this sheet is 0.25 um).
            double worst = 0;
            foreach (var sheet in sheets)
                for (int r = 0; r < sheet.Rows; ++r)
                    for (int k = 0; k < Fibers; ++k)
                        worst = Math.Max(worst, Math.Abs(sheet.Z![r, k] - Z(sheet.S![r], k)));
            output.WriteLine($"3 sheets, max error {worst * 1e3:F3} um; sheet 2: {sheets[1]}");
            Assert.True(worst < 1e-3, $"max error {worst} mm");
            // A 12 mm wave of 1800 mm: 24 mm peak to peak within 2 % (row sampling).
            Assert.InRange(sheets[1].WaveHeightMm, 23.5, 24.5);
            Assert.Equal(Pitch * Fibers, sheets[1].StripWidthMm, 9);
            Assert.Equal(sheets[1].Value(SheetValue.Rows), sheets[1].Rows);
            Assert.Equal(3000UL, gauge.Count(GaugeCounter.Frames));
        }

        [Fact]
        public void LatencyInSecondsIsTheLookaheadAtTheRowsPace()
        {
            // Rows 3 mm apart pushed every millisecond or two: a sheet's latency
            // in seconds is its look-ahead at that pace, inside the push times
            // of the rows beside the cut and of the newest row taken (the
            // host's UTC, the gauge's clock), widened by 20 ms for a coarse
            // Windows clock tick.
            using var calibration = Sensor();
            using var options = Options();
            options.LatencyMm = 1000;
            using var gauge = new Gauge(calibration, options);
            gauge.Cut(1500);
            const int rows = 1400;  // 4.2 m
            var before = new DateTime[rows];
            var after = new DateTime[rows];
            var height = new double[Fibers];
            var slope = new double[Fibers];
            for (int r = 0; r < rows; ++r)
            {
                Row(r, height, slope);
                Thread.Sleep(1);
                before[r] = DateTime.UtcNow;
                gauge.PushRow(Step * r, height, slope);
                after[r] = DateTime.UtcNow;
            }
            gauge.Flush();
            var sheets = Drain(gauge);
            Assert.Equal(2, sheets.Count);
            var first = sheets[0];
            int i = (int)Math.Ceiling(first.SEndMm / Step);  // the first row at or after the cut
            int j = (int)Math.Round((first.SEndMm + first.LookaheadMm) / Step);  // the newest row taken
            Assert.Equal(first.SEndMm + first.LookaheadMm, Step * j, 9);
            Assert.True(first.LookaheadMm >= 900, $"look-ahead {first.LookaheadMm} mm");
            var slack = TimeSpan.FromMilliseconds(20);
            double lo = (before[j] - after[i] - slack).TotalSeconds;
            double hi = (after[j] - before[i - 1] + slack).TotalSeconds;
            output.WriteLine($"look-ahead {first.LookaheadMm} mm, latency {first.LatencySeconds:F3} s (bound {lo:F3}..{hi:F3} s)");
            Assert.InRange(first.LatencySeconds, lo, hi);
            Assert.InRange(first.CutTime, before[i - 1] - slack, after[i] + slack);
            Assert.True(first.FinishedTime >= first.CutTime.AddSeconds(first.LatencySeconds) - slack);
            // The last sheet ended with the strip: it waited for nothing.
            Assert.Equal(0.0, sheets[1].LookaheadMm);
            Assert.Equal(0.0, sheets[1].LatencySeconds);
        }

        [Fact]
        public void ProvisionalSheetsComeEarlyAndCountNowhere()
        {
            // With GaugeProvisionalMm 300 each cut's sheet comes first as an
            // early answer 300 mm past the cut, then final with the same id;
            // the finals equal a gauge's without early answers, and only they
            // are counted (counters, coil statistics).
            using var calibration = Sensor();
            var runs = new List<List<Flatline.Sheet>>();
            var counted = new List<(ulong Sheets, ulong Provisional, long CoilSheets)>();
            foreach (double provisional in new[] { 0.0, 300.0 })
            {
                using var options = Options();
                options.GaugeProvisionalMm = provisional;
                using var gauge = new Gauge(calibration, options);
                using (var rules = ToleranceRules.Parse(VerdictRules))
                    gauge.SetRules(rules, thicknessMm: 4.0, SheetWidth.Measured);
                gauge.Cut(3000);
                gauge.Cut(6000);
                // The rows before the second early answer is due (row 2100
                // is at 6300 mm), then the sheets before it (the first early
                // answer and its final; the final alone without early
                // answers): the evaluator is free when the next early answer
                // falls due, on any machine. Pushed at once, a loaded machine
                // can still be evaluating the first early answer when the
                // second cut's final comes: that cut then has none.
                PushRows(gauge, 0, 2100);
                var sheets = new List<Flatline.Sheet>();
                while (sheets.Count < (provisional > 0 ? 2 : 1))
                    sheets.Add(gauge.NextSheet(60000) ?? throw new TimeoutException("no sheet in a minute"));
                PushRows(gauge, 2100, 4000);  // 12 m
                gauge.Flush();
                sheets.AddRange(Drain(gauge));
                runs.Add(sheets);
                counted.Add((gauge.Count(GaugeCounter.Sheets), gauge.Count(GaugeCounter.Provisional),
                             gauge.LastCoilStatistics()!.Sheets));
            }
            var early = runs[1];
            Assert.Equal(new[] { true, false, true, false, false }, early.Select(s => s.Provisional));
            Assert.Equal(new long[] { 1, 1, 2, 2, 3 }, early.Select(s => s.Id));
            var finals = early.Where(s => !s.Provisional).ToList();
            Assert.Equal(runs[0].Count, finals.Count);
            for (int i = 0; i < finals.Count; ++i)
            {
                Assert.Equal(runs[0][i].Z, finals[i].Z);  // bit for bit
                Assert.Equal(runs[0][i].ZoneIUnits, finals[i].ZoneIUnits);
                Assert.Equal(runs[0][i].VerdictState, finals[i].VerdictState);
            }
            foreach (int i in new[] { 0, 2 })
            {
                var p = early[i];
                var f = early[i + 1];
                Assert.True(p.Flags.HasFlag(SheetFlags.Provisional));
                Assert.Equal((f.SStartMm, f.SEndMm, f.Rows), (p.SStartMm, p.SEndMm, p.Rows));
                // At least 300 mm past the cut (later only while the previous
                // early answer is still being evaluated: under wine that can
                // take seconds), and before the final.
                Assert.True(p.LookaheadMm >= 300.0 && p.LookaheadMm < f.LookaheadMm,
                            $"early answer {p.LookaheadMm} mm past the cut, final {f.LookaheadMm} mm");
                Assert.True(f.LookaheadMm > 1500);
                // Noise-free rows: the estimate is within 1 um of the final.
                double worst = 0;
                for (int r = 0; r < p.Rows; ++r)
                    for (int k = 0; k < Fibers; ++k)
                        worst = Math.Max(worst, Math.Abs(p.Z![r, k] - f.Z![r, k]));
                Assert.True(worst < 1e-3, $"provisional differs by {worst} mm");
            }
            Assert.Equal((3UL, 0UL, 3L), counted[0]);
            Assert.Equal((3UL, 2UL, 3L), counted[1]);
        }

        [Fact]
        public void WorkersGiveTheSameSheetsBitForBit()
        {
            using var calibration = Sensor();
            var runs = new List<List<Flatline.Sheet>>();
            foreach (int workers in new[] { 0, 1, 2 })
            {
                using var options = Options(workers);
                using var gauge = new Gauge(calibration, options);
                gauge.Cut(1500);
                PushRows(gauge, 0, 1500);
                gauge.Flush();
                runs.Add(Drain(gauge));
            }
            foreach (var other in runs.Skip(1))
            {
                Assert.Equal(runs[0].Count, other.Count);
                for (int i = 0; i < other.Count; ++i)
                {
                    Assert.Equal(runs[0][i].Z, other[i].Z);
                    Assert.Equal(runs[0][i].ZoneIUnits, other[i].ZoneIUnits);
                    Assert.Equal(runs[0][i].BowMm, other[i].BowMm);
                }
            }
        }

        [Fact]
        public void TheEventRaisesEverySheetInOrderAndPollingWaits()
        {
            using var calibration = Sensor();
            using var options = Options();
            using var gauge = new Gauge(calibration, options);
            var ids = new List<long>();
            int threadOfTest = Environment.CurrentManagedThreadId;
            int raisedElsewhere = 0;
            void Handler(object? sender, SheetEventArgs e)
            {
                lock (ids)
                    ids.Add(e.Sheet.Id);
                if (Environment.CurrentManagedThreadId != threadOfTest)
                    Interlocked.Increment(ref raisedElsewhere);
            }
            gauge.SheetFinished += Handler;
            Assert.Throws<FlatlineStateException>(() => gauge.NextSheet());
            for (int c = 1; c < 5; ++c)
                gauge.Cut(1000.0 * c);
            PushRows(gauge, 0, 2000);
            gauge.Flush();
            Assert.Equal(new long[] { 1, 2, 3, 4, 5 }, ids);
            Assert.True(raisedElsewhere > 0, "the sheets are raised on the gauge's threads");
            gauge.SheetFinished -= Handler;
            Assert.Null(gauge.NextSheet(10));  // polling again: nothing left
        }

        [Fact]
        public void AHandlerExceptionComesBackFromTheNextCall()
        {
            using var calibration = Sensor();
            using var options = Options();
            using var gauge = new Gauge(calibration, options);
            gauge.SheetFinished += (sender, e) => throw new ApplicationException("the handler's own");
            PushRows(gauge, 0, 400);
            var thrown = Assert.Throws<InvalidOperationException>(() => gauge.Flush());
            Assert.IsType<ApplicationException>(thrown.InnerException);
        }

        [Fact]
        public async Task SheetsAsyncYieldsTheSheetsAsTheyCome()
        {
            using var calibration = Sensor();
            using var options = Options();
            options.LagKnots = 4;
            using var gauge = new Gauge(calibration, options);
            for (int c = 1; c < 6; ++c)
                gauge.Cut(1000.0 * c);
            using var cancel = new CancellationTokenSource(TimeSpan.FromSeconds(120));
            var reader = Task.Run(async () =>
            {
                var ids = new List<long>();
                await foreach (var sheet in gauge.SheetsAsync(cancel.Token))
                {
                    ids.Add(sheet.Id);
                    if (ids.Count == 6)
                        break;
                }
                return ids;
            });
            // The enumeration takes the sheets once it has started.
            for (int i = 0; i < 1000 && !reader.IsCompleted; ++i)
            {
                try
                {
                    gauge.NextSheet();
                    Thread.Sleep(1);
                }
                catch (FlatlineStateException)
                {
                    break;  // the callback is set: the enumeration is listening
                }
            }
            PushRows(gauge, 0, 2000);
            gauge.Flush();
            var got = await reader;
            Assert.Equal(new long[] { 1, 2, 3, 4, 5, 6 }, got);
        }

        [Fact]
        public void FramesFromASourceOnTheGaugesThread()
        {
            using var calibration = Sensor();
            using var lineOptions = new FlatlineOptions { SimFrameSpacing = 10 };
            using var line = new SimulatedLine(calibration, lineOptions);
            line.AddDefect(DefectKind.CentreBuckle, 4, 800);
            using var source = FrameSource.Simulator(line);
            using var options = new FlatlineOptions { GaugeFrameSpacing = 8, GaugeOverflow = GaugeOverflow.Wait, LagKnots = 4 };
            using var gauge = new Gauge(calibration, options);
            Assert.Throws<FlatlineStateException>(() => gauge.Start());  // no source yet
            gauge.Attach(source);
            gauge.Cut(1000);
            gauge.Start();
            Assert.Equal(1UL, gauge.Count(GaugeCounter.Acquiring));
            Assert.Throws<FlatlineStateException>(() => gauge.Flush());
            Flatline.Sheet? first = null;
            for (int i = 0; i < 600 && first == null; ++i)
                first = gauge.NextSheet(100);
            gauge.Stop();
            Assert.NotNull(first);
            Assert.Equal(1000.0, first!.SEndMm);
            Assert.Equal(100, first.Rows);
            gauge.Flush();
            var rest = gauge.NextSheet();
            Assert.NotNull(rest);
            Assert.Equal(1000.0, rest!.SStartMm);
            gauge.Attach(null);
        }

        [Fact]
        public void PushedFramesGiveSheets()
        {
            using var calibration = Sensor();
            using var lineOptions = new FlatlineOptions { SimFrameSpacing = 10 };
            using var line = new SimulatedLine(calibration, lineOptions);
            line.AddDefect(DefectKind.CentreBuckle, 4, 800);
            using var options = new FlatlineOptions { GaugeFrameSpacing = 8, GaugeOverflow = GaugeOverflow.Wait, LagKnots = 4 };
            using var gauge = new Gauge(calibration, options);
            gauge.Cut(1000);
            for (int f = 0; f < 200; ++f)
                gauge.Push(line.NextFrame());
            gauge.Flush();
            var sheets = Drain(gauge);
            Assert.Equal(2, sheets.Count);
            Assert.Equal(200UL, gauge.Count(GaugeCounter.Extracted));
            Assert.Equal(100.0, gauge.GetOption("laser_spacing"));
        }

        [Fact]
        public void ANarrowStripHasEdgesAndFibersOffIt()
        {
            // A strip 1000 mm wide, 100 mm off centre, on the 1500 mm fiber grid.
            using var calibration = Sensor();
            using var lineOptions = new FlatlineOptions { SimFrameSpacing = 10, SimStripWidth = 1000 };
            lineOptions.Set("sim_strip_offset", 100);
            lineOptions.Set("sim_surround", 2); // the roller table beside the strip
            using var line = new SimulatedLine(calibration, lineOptions);
            line.AddDefect(DefectKind.CentreBuckle, 4, 800);
            using var options = new FlatlineOptions { GaugeFrameSpacing = 8, GaugeOverflow = GaugeOverflow.Wait, LagKnots = 4 };
            options.Set("gauge_keep_maps", 1);
            using var gauge = new Gauge(calibration, options);
            for (int f = 0; f < 200; ++f)
                gauge.Push(line.NextFrame());
            gauge.Flush();
            var sheets = Drain(gauge);
            Assert.Single(sheets);
            var sheet = sheets[0];
            // The extractor's edges, to a fraction of a camera column (about
            // 1 mm), smoothed along the sheet: within 2 mm.
            Assert.True(Math.Abs(sheet.StripWidthMm - 1000) < 2, $"width {sheet.StripWidthMm}");
            Assert.True(Math.Abs(sheet.StripCentreMm - 100) < 2, $"centre {sheet.StripCentreMm}");
            Assert.True(sheet.StripWidthMinMm <= sheet.StripWidthMm && sheet.StripWidthMm <= sheet.StripWidthMaxMm);
            // Fibers a pitch and a half (45 mm) beside the strip are off it in every row.
            for (int k = 0; k < Fibers; ++k)
            {
                double x = -750 + Pitch * k;
                if (x > -445 && x < 645)
                    continue;
                for (int r = 0; r < sheet.Rows; ++r)
                {
                    Assert.Equal(ReconFlags.OffStrip, sheet.ZFlags![r, k]);
                    Assert.True(double.IsNaN(sheet.Z![r, k]));
                }
            }
            for (int j = 0; j < sheet.ZoneStripX.Length; ++j)
            {
                if ((sheet.ZoneFlags[j] & ZoneFlags.OffStrip) != 0)
                    Assert.True(double.IsNaN(sheet.ZoneStripX[j]));
                else
                    Assert.True(Math.Abs(sheet.ZoneStripX[j]) < 500);
            }
        }

        [Fact]
        public void AGaugeNobodyDisposesIsFreedByItsFinalizer()
        {
            using var calibration = Sensor();
            long before = GaugeHandle.Live;
            MakeAndDrop(calibration);
            for (int i = 0; i < 20 && GaugeHandle.Live > before; ++i)
            {
                GC.Collect();
                GC.WaitForPendingFinalizers();
            }
            // Its handler was set and its strip open: the finalizer removes
            // the callback, stops the workers and frees everything.
            Assert.Equal(before, GaugeHandle.Live);
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static void MakeAndDrop(Calibration calibration)
        {
            var gauge = new Gauge(calibration);
            gauge.SheetFinished += (sender, e) => { };
            gauge.Cut(600);
            PushRows(gauge, 0, 400);
        }

        [Fact]
        public void BadInputThrowsWithTheLibrarysMessage()
        {
            using var calibration = Sensor();
            using (var foreign = new FlatlineOptions { SimSeed = 3 })
            {
                var e = Assert.Throws<InvalidArgumentException>(() => new Gauge(calibration, foreign));
                Assert.Contains("sim_seed", e.Message);
            }
            using var gauge = new Gauge(calibration);
            Assert.Throws<ArgumentException>(() => gauge.Push(new byte[10, 10], 0.0));
            Assert.Throws<ArgumentNullException>(() => gauge.PushRow(0.0, null!, new double[Fibers]));  // null on purpose: the check under test
            Assert.Throws<InvalidArgumentException>(() => gauge.PushRow(0.0, new double[Fibers + 1], new double[Fibers + 1]));
            Assert.Throws<InvalidArgumentException>(() => gauge.Push(new byte[240, 2048], double.NaN));
            gauge.Cut(100);
            var order = Assert.Throws<InvalidArgumentException>(() => gauge.Cut(50));
            Assert.Contains("previous cut", order.Message);
            Assert.Throws<ArgumentOutOfRangeException>(() => gauge.NextSheet(-1));
            gauge.Dispose();
            Assert.Throws<ObjectDisposedException>(() => gauge.Cut(200));
            gauge.Dispose();  // idempotent
        }

        private const string VerdictRules = @"{
  ""format"": ""flatline-tolerances"", ""version"": 1, ""name"": ""c# gauge test"",
  ""rules"": [
    { ""name"": ""1/2 m tight"", ""measure"": ""straightedge_along"", ""length_mm"": 500,
      ""bands"": [ { ""thickness_mm"": [1, 10], ""width_mm"": [0, 3000], ""limit"": 1.9 } ] },
    { ""name"": ""1/2 m loose"", ""measure"": ""straightedge_along"", ""length_mm"": 500,
      ""bands"": [ { ""thickness_mm"": [1, 10], ""width_mm"": [0, 3000], ""limit"": 2.1 } ] }
  ]
}";

        [Fact]
        public void SheetsCarryTheirVerdictAndTheCoilItsStatistics()
        {
            // The strip waves along travel as 2 sin(2 pi s / 1000) mm across its
            // whole width: under a 500 mm straightedge the deviation is
            // A (1 - cos(pi L / P)) = 2 mm, so the 1.9 mm rule fails and the 2.1
            // mm one passes.
            using var calibration = Sensor();
            using var options = Options();
            using var gauge = new Gauge(calibration, options);
            Assert.Null(gauge.CurrentCoilStatistics());
            using (var rules = ToleranceRules.Parse(VerdictRules))
            {
                gauge.SetRules(rules, thicknessMm: 4.0, SheetWidth.Measured);
                Assert.Same(rules, gauge.Rules);
            }  // the gauge keeps its own copy
            gauge.Cut(3000);
            gauge.Cut(6000);
            var height = new double[Fibers];
            var slope = new double[Fibers];
            double Bow(double s) => 2.0 * Math.Sin(2 * Math.PI * s / 1000.0);
            for (int r = 0; r < 3000; ++r)
            {
                double s = Step * r;
                for (int k = 0; k < Fibers; ++k)
                {
                    height[k] = 0.5 * (Bow(s - 50) + Bow(s + 50));
                    slope[k] = (Bow(s + 50) - Bow(s - 50)) / 100.0;
                }
                gauge.PushRow(s, height, slope);
            }
            gauge.Flush();
            var sheets = Drain(gauge);
            Assert.Equal(3, sheets.Count);
            foreach (var sheet in sheets)
            {
                var verdict = sheet.Verdict;
                Assert.NotNull(verdict);
                Assert.Equal("1/2 m tight", verdict![0].Rule.Name);
                Assert.Equal(VerdictState.Fail, verdict[0].State);
                Assert.Equal(VerdictState.Pass, verdict[1].State);
                Assert.Equal(1, sheet.FailedRules);
                // Rows every 3 mm: at most A pi h / P = 0.019 mm below 2 mm; the
                // noise-free gauge is within micrometres of the sheet.
                Assert.InRange(verdict[0].Worst, 2.0 - 0.02, 2.0 + 0.001);
                Assert.Equal(1.9 - verdict[0].Worst, verdict[0].Margin, 12);
            }
            var coil = gauge.LastCoilStatistics();
            Assert.NotNull(coil);
            Assert.True(coil!.Finished);
            Assert.Equal((1L, 3L, 0L, 3L), (coil.Coil, coil.Sheets, coil.Passed, coil.Failed));
            Assert.Equal(3, coil.Rules[0].Failed);
            Assert.Equal(sheets.Max(s => s.Verdict![0].Worst), coil.Rules[0].WorstMax);
            Assert.Equal(3, coil.Rules[0].Histogram[10]);  // 2 / 1.9 in (1.0, 1.1]
            Assert.Equal(3, coil.Rules[1].Histogram[9]);   // 2 / 2.1 in (0.9, 1.0]
            var now = gauge.CurrentCoilStatistics();
            Assert.Equal((0L, 0L), (now!.Coil, now.Sheets));
            gauge.ClearRules();
            Assert.Null(gauge.Rules);
            Assert.Null(gauge.CurrentCoilStatistics());
            Assert.Throws<InvalidArgumentException>(() => gauge.SetRules(ToleranceRules.Parse(VerdictRules), -1.0, SheetWidth.Measured));
            Assert.Throws<ArgumentOutOfRangeException>(() => SheetWidth.Nominal(0));
        }

        [Fact]
        public void ASheetNoBandCoversIsNotJudgedNeverPassed()
        {
            // The rules' bands are 1..10 mm thick: a 0.5 mm sheet is in none.
            // Each sheet is not judged, and the coil counts 0 passed, 0 failed,
            // 2 not judged.
            using var calibration = Sensor();
            using var options = Options();
            using var gauge = new Gauge(calibration, options);
            using (var rules = ToleranceRules.Parse(VerdictRules))
                gauge.SetRules(rules, 0.5, SheetWidth.Nominal(1500));
            gauge.Cut(3000);
            var zero = new double[Fibers];
            for (int r = 0; r < 2000; ++r)
                gauge.PushRow(Step * r, zero, zero);
            gauge.Flush();
            var sheets = Drain(gauge);
            Assert.Equal(2, sheets.Count);
            Assert.All(sheets, s => Assert.Equal(VerdictState.NotJudged, s.VerdictState));
            Assert.All(sheets, s => Assert.Equal(1.0, s.Coverage));
            var coil = gauge.LastCoilStatistics();
            Assert.NotNull(coil);
            Assert.Equal((2L, 0L, 0L, 2L, 0L), (coil!.Sheets, coil.Passed, coil.Failed, coil.NotJudged, coil.Judged));
        }

        [Theory]
        [InlineData(0)]
        [InlineData(1)]
        [InlineData(2)]
        public void EveryCallFromASheetHandlerReturnsAtOnce(int workers)
        {
            // Each call of the gauge from inside its own SheetFinished handler
            // either works (Cut is queued, Count, SetRules, statistics) or
            // throws FlatlineStateException at once: none waits for itself.
            using var calibration = Sensor();
            using var options = Options(workers);
            options.LagKnots = 4;
            using var gauge = new Gauge(calibration, options);
            using var rules = ToleranceRules.Parse(VerdictRules);
            var outcome = new Dictionary<string, string>();
            double slowest = 0;
            int seen = 0;
            var zero = new double[Fibers];
            using var firstDone = new ManualResetEventSlim();
            gauge.SheetFinished += (sender, e) =>
            {
                if (seen++ > 0)
                    return;
                void Try(string name, Action call)
                {
                    var watch = System.Diagnostics.Stopwatch.StartNew();
                    try
                    {
                        call();
                        outcome[name] = "ok";
                    }
                    catch (Exception x)
                    {
                        outcome[name] = x.GetType().Name;
                    }
                    slowest = Math.Max(slowest, watch.Elapsed.TotalSeconds);
                }
                Try("PushRow", () => gauge.PushRow(1e6, zero, zero));
                Try("Push", () => gauge.Push(new byte[gauge.FrameHeight, gauge.FrameWidth], 1e6));
                Try("Cut", () => gauge.Cut(4000));
                Try("Flush", () => gauge.Flush());
                Try("Start", () => gauge.Start());
                Try("Stop", () => gauge.Stop());
                Try("NextSheet", () => gauge.NextSheet(100));
                Try("Count", () => gauge.Count(GaugeCounter.Sheets));
                Try("SetRules", () => gauge.SetRules(rules, 2.0, SheetWidth.Measured));
                Try("Statistics", () => gauge.CurrentCoilStatistics());
                Try("GetOption", () => gauge.GetOption("gauge_workers"));
                firstDone.Set();
            };
            gauge.Cut(1000);
            // Rows to 3000 mm: the first sheet (to 1000 mm) finishes within
            // the lag of 4 knots. The rest only after its handler ran, so
            // its cut at 4000 mm lies ahead of every row (a flush that came
            // first would end the strip before the cut is seen).
            PushRows(gauge, 0, 1000);
            Assert.True(firstDone.Wait(TimeSpan.FromSeconds(30), TestContext.Current.CancellationToken),
                        "the first sheet did not finish");
            PushRows(gauge, 1000, 2000);
            gauge.Flush();
            Assert.InRange(slowest, 0.0, 1.0);
            foreach (var ok in new[] { "Cut", "Count", "SetRules", "Statistics", "GetOption" })
                Assert.Equal("ok", outcome[ok]);
            foreach (var refused in new[] { "PushRow", "Push", "Flush", "Start", "Stop", "NextSheet" })
                Assert.Equal(nameof(FlatlineStateException), outcome[refused]);
            // The cut given inside took effect: sheets end at 1000, 4000, the flush.
            Assert.Equal(3, seen);
            Assert.Equal(3UL, gauge.Count(GaugeCounter.Sheets));
            Assert.Equal(0UL, gauge.Count(GaugeCounter.CutsIgnored));
        }

        [Fact]
        public void ASecondThreadPushingIsRefusedAndTheGaugeGoesOn()
        {
            using var calibration = Sensor();
            using var options = Options(1);
            options.LagKnots = 4;
            options.GaugeQueueFrames = 1;
            options.GaugeReversalLength = 1e8;  // back to 0 is a short reversal: skipped
            using var gauge = new Gauge(calibration, options);
            for (int c = 600; c < 9000; c += 600)
                gauge.Cut(c);
            PushRows(gauge, 0, 10);
            int refused = 0, taken = 0;
            using var stop = new ManualResetEventSlim();
            var zero = new double[Fibers];
            var other = new Thread(() =>
            {
                while (!stop.IsSet)
                {
                    try
                    {
                        gauge.PushRow(0.0, zero, zero);
                        ++taken;
                    }
                    catch (FlatlineStateException e)
                    {
                        Assert.Contains("another thread is pushing", e.Message);
                        ++refused;
                    }
                    stop.Wait(1);
                }
            });
            other.Start();
            try
            {
                var height = new double[Fibers];
                var slope = new double[Fibers];
                for (int r = 10; r < 3000;)
                {
                    Row(r, height, slope);
                    try
                    {
                        gauge.PushRow(Step * r, height, slope);
                        ++r;
                    }
                    catch (FlatlineStateException)
                    {
                        // refused too when it comes while the other pushes
                    }
                }
            }
            finally
            {
                stop.Set();
                other.Join();
            }
            gauge.Flush();
            var sheets = Drain(gauge);
            Assert.True(refused > 0, "the second thread never met the first one's push");
            Assert.Equal(3000, sheets.Sum(s => s.Rows));
            Assert.Equal((ulong)(3000 + taken), gauge.Count(GaugeCounter.Frames));
        }

        private static void WritePng(string path, byte[,] image)
        {
            int h = image.GetLength(0), w = image.GetLength(1);
            var raw = new System.IO.MemoryStream();
            for (int y = 0; y < h; ++y)
            {
                raw.WriteByte(0);  // filter: none
                for (int x = 0; x < w; ++x)
                    raw.WriteByte(image[y, x]);
            }
            var packed = new System.IO.MemoryStream();
            packed.Write(new byte[] { 0x78, 0x01 }, 0, 2);  // zlib header, fastest
            using (var deflate = new System.IO.Compression.DeflateStream(packed, System.IO.Compression.CompressionLevel.Fastest, true))
                raw.WriteTo(deflate);
            uint adler = Adler32(raw.ToArray());
            packed.Write(BigEndian(adler), 0, 4);
            using var file = System.IO.File.Create(path);
            file.Write(new byte[] { 0x89, (byte)'P', (byte)'N', (byte)'G', 0x0D, 0x0A, 0x1A, 0x0A }, 0, 8);
            var header = new byte[13];
            Array.Copy(BigEndian((uint)w), 0, header, 0, 4);
            Array.Copy(BigEndian((uint)h), 0, header, 4, 4);
            header[8] = 8;  // 8-bit grey
            Chunk(file, "IHDR", header);
            Chunk(file, "IDAT", packed.ToArray());
            Chunk(file, "IEND", Array.Empty<byte>());
        }

        private static byte[] BigEndian(uint v) => new[] { (byte)(v >> 24), (byte)(v >> 16), (byte)(v >> 8), (byte)v };

        private static uint Adler32(byte[] data)
        {
            uint a = 1, b = 0;
            foreach (byte d in data)
            {
                a = (a + d) % 65521;
                b = (b + a) % 65521;
            }
            return (b << 16) | a;
        }

        private static void Chunk(System.IO.Stream f, string type, byte[] body)
        {
            var tag = System.Text.Encoding.ASCII.GetBytes(type);
            f.Write(BigEndian((uint)body.Length), 0, 4);
            f.Write(tag, 0, 4);
            f.Write(body, 0, body.Length);
            uint crc = 0xFFFFFFFF;
            foreach (byte x in tag.Concat(body))
            {
                crc ^= x;
                for (int k = 0; k < 8; ++k)
                    crc = (crc & 1) != 0 ? (crc >> 1) ^ 0xEDB88320 : crc >> 1;
            }
            f.Write(BigEndian(~crc), 0, 4);
        }

        [Fact]
        public async Task RunAsyncRunsARecordingToItsEnd()
        {
            // 150 recorded frames 10 mm apart, cuts at 500 and 1000 mm: the
            // 3 sheets, the last after the source's end, nothing dropped.
            string dir = System.IO.Path.Combine(System.IO.Path.GetTempPath(), "flatline-run-" + Guid.NewGuid().ToString("N"));
            System.IO.Directory.CreateDirectory(dir);
            try
            {
                using var calibration = Calibration.Reference(firstRow: 900, rows: 240, firstXMm: -750, pitchMm: 10, fibers: 151);
                using (var lineOptions = new FlatlineOptions { SimFrameSpacing = 10 })
                using (var line = new SimulatedLine(calibration, lineOptions))
                {
                    line.AddDefect(DefectKind.CentreBuckle, 4, 800);
                    for (int i = 0; i < 150; ++i)
                        WritePng(System.IO.Path.Combine(dir, $"frame_{i:000}.png"), line.NextFrame().Pixels8!);
                }
                using var options = new FlatlineOptions { GaugeFrameSpacing = 8, LagKnots = 4, GaugeQueueFrames = 4 };
                using var gauge = new Gauge(calibration, options);
                gauge.Cut(500);
                gauge.Cut(1000);
                using var sourceOptions = new FlatlineOptions { SourceEncoderStep = 10 };
                using var source = FrameSource.ImageDirectory(dir, null, sourceOptions);
                var sheets = new List<Flatline.Sheet>();
                await foreach (var sheet in gauge.RunAsync(source, TestContext.Current.CancellationToken))
                    sheets.Add(sheet);
                Assert.Equal(new long[] { 1, 2, 3 }, sheets.Select(s => s.Id));
                Assert.Equal(500.0, sheets[0].SEndMm);
                Assert.Equal(1000.0, sheets[1].SEndMm);
                Assert.True((sheets[2].Flags & SheetFlags.Flushed) != 0);
                Assert.Equal(150UL, gauge.Count(GaugeCounter.Frames));
                Assert.Equal(0UL, gauge.Count(GaugeCounter.Dropped));
                Assert.Equal(150L, sheets.Sum(s => (long)s.Rows) + (long)gauge.Count(GaugeCounter.NoStrip));
            }
            finally
            {
                System.IO.Directory.Delete(dir, true);
            }
        }

        [Fact]
        public void TheLogTellsDropsIgnoredCutsAndSaturation()
        {
            // A gauge that drops frames (a queue of 1, frames pushed faster
            // than one worker extracts them), a cut for a strip that ended,
            // and an overexposed line: a message for each. (The log is the
            // process's: other tests' messages are told apart by content.)
            var got = new System.Collections.Concurrent.ConcurrentQueue<FlatlineLogEventArgs>();
            EventHandler<FlatlineLogEventArgs> handler = (sender, e) => got.Enqueue(e);
            using var calibration = Calibration.Reference(firstRow: 900, rows: 240, firstXMm: -750, pitchMm: 10, fibers: 151);
            var frames = new List<byte[,]>();
            using (var lineOptions = new FlatlineOptions { SimFrameSpacing = 10 })
            {
                lineOptions.Set("sim_line_peak", 1.5);
                using var line = new SimulatedLine(calibration, lineOptions);
                for (int i = 0; i < 200; ++i)
                    frames.Add(line.NextFrame().Pixels8!);
            }
            FlatlineLog.Message += handler;
            try
            {
                using var options = new FlatlineOptions
                {
                    GaugeWorkers = 1, GaugeQueueFrames = 1, GaugeOverflow = GaugeOverflow.Drop, GaugeFrameSpacing = 8,
                    LagKnots = 4,
                };
                using var gauge = new Gauge(calibration, options);
                for (int i = 0; i < frames.Count; ++i)
                    gauge.Push(frames[i], 10.0 * i);
                gauge.Flush();
                gauge.Cut(1234);  // the next strip's head (5000 mm) is past it: ignored
                gauge.Push(frames[0], 5000);
                gauge.Flush();
                Assert.True(gauge.Count(GaugeCounter.Dropped) > 0);
            }
            finally
            {
                FlatlineLog.Message -= handler;  // returns once no message is in progress
            }
            var mine = got.Where(e => e.Component == "gauge").ToList();
            Assert.Contains(mine, e => e.Level == FlatlineLogLevel.Warning && e.Message.Contains(" dropped: "));
            Assert.Single(mine, e => e.Level == FlatlineLogLevel.Warning &&
                                     e.Message.Contains("cut ignored, the last at encoder 1234.0 mm"));
            Assert.Contains(mine, e => e.Level == FlatlineLogLevel.Warning && e.Message.Contains(" are saturated "));
            Assert.Contains(mine, e => e.Level == FlatlineLogLevel.Information && e.Message.Contains("the strip's head at s = 5000.0 mm"));
        }
    }
}
