// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.Diagnostics;
using System.Runtime.CompilerServices;
using Xunit;
using Flatline.Testing;

namespace Flatline.Tests
{
    public class GcStressTests
    {
        private const int Count = 10_000;
        private readonly ITestOutputHelper output;

        public GcStressTests(ITestOutputHelper output) => this.output = output;

        private static FlatlineOptions SmallOptions() =>
            new FlatlineOptions { RowCapacity = 1024, LagKnots = 8 };

        // Not inlined, so no reference survives in this frame's registers.
        [MethodImpl(MethodImplOptions.NoInlining)]
        private static void Abandon(int count, FlatlineOptions options, List<Reconstructor>? keep)
        {
            var row = new double[4];
            for (int i = 0; i < count; ++i)
            {
                var recon = new Reconstructor(4, options);
                recon.Push(i, row, row);  // used, so the engine is really touched
                keep?.Add(recon);
            }
        }

        /// <summary>Creates 10,000 reconstructors held in a list, measures,
        /// and drops the list with the frame (no JIT temporary outlives it).</summary>
        [MethodImpl(MethodImplOptions.NoInlining)]
        private static long KeepAliveThenDrop(FlatlineOptions options, long liveBefore)
        {
            var kept = new List<Reconstructor>(Count);
            Abandon(Count, options, kept);
            long rss = Resident();
            Assert.Equal(liveBefore + Count, ReconHandle.Live);
            return rss;
        }

        // glibc keeps freed heap pages for reuse; malloc_trim hands them back
        // to the system, so the resident size shows what is really still held.
        [System.Runtime.InteropServices.DllImport("libc", EntryPoint = "malloc_trim")]
        private static extern int MallocTrim(UIntPtr pad);

        private static void CollectEverything()
        {
            for (int i = 0; i < 3; ++i)
            {
                GC.Collect();
                GC.WaitForPendingFinalizers();
            }
            GC.Collect();
            if (OperatingSystem.IsLinux())
                MallocTrim(UIntPtr.Zero);
        }

        private static long Resident()
        {
            using var self = Process.GetCurrentProcess();
            self.Refresh();
            return self.WorkingSet64;
        }

        [Fact]
        public void TenThousandUndisposedReconstructorsAreFreedByTheFinalizer()
        {
            using var options = SmallOptions();
            CollectEverything();
            long liveBefore = ReconHandle.Live;
            long rssBefore = Resident();

            // What 10,000 live reconstructors hold: the leak we must not have.
            long rssAlive = KeepAliveThenDrop(options, liveBefore);
            CollectEverything();
            long rssAfterFirst = Resident();
            Assert.Equal(liveBefore, ReconHandle.Live);

            // Now without keeping or disposing anything, twice: had the
            // finalizer not freed them, each round would add what 10,000 hold.
            Abandon(Count, options, null);
            CollectEverything();
            Abandon(Count, options, null);
            CollectEverything();
            long rssEnd = Resident();
            Assert.Equal(liveBefore, ReconHandle.Live);

            long held = rssAlive - rssBefore;
            output.WriteLine($"resident: before {rssBefore >> 20} MiB, 10,000 alive {rssAlive >> 20} MiB " +
                             $"(+{held >> 20} MiB), after collect {rssAfterFirst >> 20} MiB, " +
                             $"after 20,000 more undisposed {rssEnd >> 20} MiB " +
                             $"(+{(rssEnd - rssAfterFirst) >> 20} MiB)");
            // 10,000 engines with 1024 rows x 4 fibers hold at least their row
            // rings, 9 bytes per row and fiber (recon.h): 369 MB in all. The
            // resident growth shows less where the allocator reuses pages
            // that earlier tests freed and it kept (the "before" figure holds
            // them: 396 MiB once, with 322 MiB grown): at least half the
            // rings shows that the measurement sees the engines.
            long rings = 9L * 1024 * 4 * Count;
            Assert.True(held > rings / 2, $"10,000 live reconstructors hold only {held >> 20} MiB");
            // Memory returns: the two undisposed rounds reuse what was freed.
            // A leak would add 2 x held; allow a tenth of one held for the
            // allocator's and the GC's own slack.
            Assert.True(rssEnd - rssAfterFirst < held / 10,
                        $"memory grew by {(rssEnd - rssAfterFirst) >> 20} MiB over 20,000 undisposed objects");
            // And most of it went back to the system after the first collect.
            Assert.True(rssAfterFirst - rssBefore < held / 2,
                        $"only {(rssAlive - rssAfterFirst) >> 20} of {held >> 20} MiB returned");
        }

        [Fact]
        public void UndisposedOptionsAreFreedByTheFinalizer()
        {
            CollectEverything();
            long before = OptionsHandle.Live;
            MakeOptions();
            CollectEverything();
            Assert.Equal(before, OptionsHandle.Live);
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static void MakeOptions()
        {
            for (int i = 0; i < Count; ++i)
                new FlatlineOptions().MaxGap = 100 + i % 50;
        }
    
        [MethodImpl(MethodImplOptions.NoInlining)]
        private static void AbandonCalibrations(int count)
        {
            for (int i = 0; i < count; ++i)
                Assert.True(Calibration.Reference(960, 128, -1000, 100, 21).IsFinished);
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static void AbandonLines(int count, Calibration calib)
        {
            for (int i = 0; i < count; ++i)
                Assert.Equal(1, new SimulatedLine(calib).NextRows(1).Rows);  // used, so it is really touched
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static void AbandonExtractors(int count, Calibration calib)
        {
            for (int i = 0; i < count; ++i)
                Assert.Equal(21, new Extractor(calib).Fibers);
        }

        [Fact]
        public void UndisposedCalibrationsSimulatedLinesAndExtractorsAreFreedByTheFinalizer()
        {
            using var calib = SimulatedLineTests.SmallSensor();
            CollectEverything();
            long calibsBefore = CalibHandle.Live, linesBefore = SimHandle.Live, extractorsBefore = ExtractorHandle.Live;
            long rssBefore = Resident();
            var clock = Stopwatch.StartNew();
            AbandonCalibrations(Count);
            // Each line holds a 4-byte-per-pixel frame scratch of 2048 x 128
            // px, 1 MiB (sim.h): 1,000 of them leaked would be 1 GiB.
            const int lines = 1000;
            AbandonLines(lines, calib);
            AbandonExtractors(Count, calib);
            double seconds = clock.Elapsed.TotalSeconds;
            CollectEverything();
            long rssAfter = Resident();
            output.WriteLine($"{Count} calibrations, {lines} simulated lines and {Count} extractors undisposed in {seconds:F1} s; " +
                             $"resident before {rssBefore >> 20} MiB, after collect {rssAfter >> 20} MiB");
            Assert.Equal(calibsBefore, CalibHandle.Live);
            Assert.Equal(linesBefore, SimHandle.Live);
            Assert.Equal(extractorsBefore, ExtractorHandle.Live);
            long scratch = 4L * 2048 * 128 * lines;
            Assert.True(rssAfter - rssBefore < scratch / 4,
                        $"memory grew by {(rssAfter - rssBefore) >> 20} MiB over {lines} undisposed lines");
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static void AbandonFlatness(int count, FlatlineOptions options)
        {
            double[] x = { 0, 100, 200, 300, 400 };
            for (int i = 0; i < count; ++i)
                Assert.Equal(5, new Flatness(x, options).Fibers);
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static void AbandonSources(int count, SimulatedLine line)
        {
            for (int i = 0; i < count; ++i)
            {
                var source = FrameSource.Simulator(line);
                source.Start();
                Assert.NotNull(source.Next());   // used: its frame buffer is touched
            }
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static void AbandonBuses(int count)
        {
            for (int i = 0; i < count; ++i)
                Assert.Equal(0, new U3VSimBus().AddCamera("Flatline", "Gc", "G", 64, 16));
        }

        [Fact]
        public void UndisposedFlatnessSourcesAndSimulatedBusesAreFreedByTheFinalizer()
        {
            using var calib = SimulatedLineTests.SmallSensor();
            using var line = new SimulatedLine(calib);
            using var options = new FlatlineOptions { FlatRowCapacity = 64 };
            CollectEverything();
            long flatBefore = FlatnessHandle.Live, sourcesBefore = SourceHandle.Live, busesBefore = U3VSimHandle.Live;
            long linesBefore = SimHandle.Live;
            long rssBefore = Resident();
            var clock = Stopwatch.StartNew();
            AbandonFlatness(Count, options);
            // Each source holds one 2048 x 128 px Mono8 frame buffer, 256 KiB
            // (source.h): 1,000 of them leaked would be 250 MiB.
            const int sources = 1000;
            AbandonSources(sources, line);
            AbandonBuses(sources);
            double seconds = clock.Elapsed.TotalSeconds;
            CollectEverything();
            long rssAfter = Resident();
            output.WriteLine($"{Count} flatness objects, {sources} frame sources and {sources} simulated buses " +
                             $"undisposed in {seconds:F1} s; resident before {rssBefore >> 20} MiB, after collect " +
                             $"{rssAfter >> 20} MiB");
            Assert.Equal(flatBefore, FlatnessHandle.Live);
            Assert.Equal(sourcesBefore, SourceHandle.Live);
            Assert.Equal(busesBefore, U3VSimHandle.Live);
            // The sources held the line's handle; released, it is the test's again.
            Assert.Equal(linesBefore, SimHandle.Live);
            Assert.Equal(1, line.NextRows(1).Rows);
            long frames = 2048L * 128 * sources;
            Assert.True(rssAfter - rssBefore < frames / 4,
                        $"memory grew by {(rssAfter - rssBefore) >> 20} MiB over {sources} undisposed sources");
        }
    }
}
