// SPDX-License-Identifier: Apache-2.0
using System;
using System.IO;
using System.Runtime.CompilerServices;
using System.Runtime.InteropServices;
using Xunit;
using Flatline.Testing;

namespace Flatline.Tests
{
    /// <summary>Writes baseline TIFF files (little-endian, one uncompressed
    /// strip, grayscale 8 or 16 bits): what a line recorder saves, and
    /// simple enough to write here without an imaging library.</summary>
    internal static class Tiff
    {
        public static void Write(string path, byte[,] pixels) =>
            Write(path, pixels.GetLength(1), pixels.GetLength(0), 8, (w, r, c) => w.Write(pixels[r, c]));

        public static void Write(string path, ushort[,] pixels) =>
            Write(path, pixels.GetLength(1), pixels.GetLength(0), 16, (w, r, c) => w.Write(pixels[r, c]));

        private static void Write(string path, int width, int height, int bits, Action<BinaryWriter, int, int> pixel)
        {
            const int Entries = 9, Data = 8 + 2 + Entries * 12 + 4;
            int bytes = width * height * bits / 8;
            using var w = new BinaryWriter(File.Create(path));
            w.Write((byte)'I'); w.Write((byte)'I'); w.Write((ushort)42); w.Write(8u);
            w.Write((ushort)Entries);
            void Entry(ushort tag, ushort type, uint value)
            {
                w.Write(tag); w.Write(type); w.Write(1u); w.Write(value);
            }
            Entry(256, 4, (uint)width);      // ImageWidth
            Entry(257, 4, (uint)height);     // ImageLength
            Entry(258, 3, (uint)bits);       // BitsPerSample
            Entry(259, 3, 1);                // Compression: none
            Entry(262, 3, 1);                // PhotometricInterpretation: BlackIsZero
            Entry(273, 4, Data);             // StripOffsets
            Entry(277, 3, 1);                // SamplesPerPixel
            Entry(278, 4, (uint)height);     // RowsPerStrip
            Entry(279, 4, (uint)bytes);      // StripByteCounts
            w.Write(0u);                     // no next IFD
            for (int r = 0; r < height; ++r)
                for (int c = 0; c < width; ++c)
                    pixel(w, r, c);
        }
    }

    public class FrameSourceTests : IDisposable
    {
        private readonly ITestOutputHelper output;
        private readonly string folder;

        public FrameSourceTests(ITestOutputHelper output)
        {
            this.output = output;
            folder = Path.Combine(Path.GetTempPath(), "flatline-cs-" + Guid.NewGuid().ToString("N"));
            Directory.CreateDirectory(folder);
        }

        public void Dispose() => Directory.Delete(folder, recursive: true);

        private static Calibration SmallSensor() =>
            Calibration.Reference(firstRow: 960, rows: 128, firstXMm: -800, pitchMm: 20, fibers: 81);

        /// <summary>Byte-for-byte equality of two frames (fast: xunit's
        /// element-wise comparison of 2D arrays takes seconds at 512 KB).</summary>
        internal static bool SameBytes(byte[,] a, byte[,] b) =>
            a.GetLength(0) == b.GetLength(0) && a.GetLength(1) == b.GetLength(1) &&
            MemoryMarshal.CreateReadOnlySpan(ref a[0, 0], a.Length)
                         .SequenceEqual(MemoryMarshal.CreateReadOnlySpan(ref b[0, 0], b.Length));

        private static SimulatedLine Line(Calibration calib)
        {
            var options = new FlatlineOptions { SimFrameSpacing = 5, SimSeed = 11 };
            var line = new SimulatedLine(calib, options);
            line.AddDefect(DefectKind.CentreBuckle, 8, 1500);
            return line;
        }

        [Fact]
        public void ASimulatorSourceDeliversTheLinesFramesBitwise()
        {
            using var calib = SmallSensor();
            using var direct = Line(calib);
            using var source = FrameSource.Simulator(Line(calib));
            Assert.Equal(SourceKind.Simulator, source.Kind);
            Assert.Throws<FlatlineStateException>(() => source.Next());   // before Start
            source.Start();
            Frame? reused = null;
            for (int f = 0; f < 5; ++f)
            {
                var expected = direct.NextFrame();
                var frame = source.Take(1000, reused);
                if (reused != null)
                    Assert.Same(reused, frame);  // same size and format: copied into it
                reused = frame;
                Assert.Equal(PixelFormat.Mono8, frame.Format);
                Assert.Equal((ulong)f, frame.BlockId);
                Assert.Equal(expected.EncoderMm, frame.EncoderMm);
                Assert.Equal(5.0 * f, frame.EncoderMm);
                Assert.True(SameBytes(expected.Mono8(), frame.Mono8()), $"frame {f} differs");
                Assert.Equal(2048, frame.StrideBytes);
            }
            Assert.Equal(5UL, source.Count(SourceCounter.Frames));
            Assert.Equal(0UL, source.Counters[SourceCounter.Dropped]);
            Assert.Equal("", source.StreamError);
            Assert.Throws<FlatlineStateException>(() => source.Start());  // already started
            Assert.Throws<FlatlineStateException>(() => source.GetCameraString(CameraString.Model));
        }

        [Fact]
        public void ImageFilesGiveTheirPixelsAndTheEncoderPositionsOfTheCsvOrTheFixedStep()
        {
            var random = new Random(5);
            var images = new byte[3][,];
            var paths = new string[3];
            for (int i = 0; i < 3; ++i)
            {
                images[i] = new byte[24, 40];
                for (int r = 0; r < 24; ++r)
                    for (int c = 0; c < 40; ++c)
                        images[i][r, c] = (byte)random.Next(256);
                paths[i] = Path.Combine(folder, $"frame{i}.tif");
                Tiff.Write(paths[i], images[i]);
            }
            string csv = Path.Combine(folder, "encoder.csv");
            File.WriteAllText(csv, "file,encoder_mm\nframe0.tif,10.5\nframe1.tif,13.25\nframe2.tif,16\n");
            using (var source = FrameSource.Images(paths, csv))
            {
                Assert.Equal(SourceKind.Images, source.Kind);
                source.Start();
                double[] encoder = { 10.5, 13.25, 16.0 };
                for (int i = 0; i < 3; ++i)
                {
                    var frame = source.Take();
                    Assert.Equal(images[i], frame.Pixels8);
                    Assert.Equal(encoder[i], frame.EncoderMm);
                    Assert.Equal((ulong)i, frame.BlockId);
                }
                Assert.Null(source.Next());  // end of the sequence
            }
            // The directory, sorted by name, with a fixed step.
            using (var options = new FlatlineOptions { SourceEncoderStart = 100, SourceEncoderStep = 2.5 })
            using (var source = FrameSource.ImageDirectory(folder, null, options))
            {
                source.Start();
                for (int i = 0; i < 3; ++i)
                {
                    var frame = source.Take();
                    Assert.Equal(images[i], frame.Pixels8);
                    Assert.Equal(100 + 2.5 * i, frame.EncoderMm);
                }
                Assert.Null(source.Next());
            }
            // 16-bit files holding 12-bit data.
            var deep = new ushort[16, 20];
            for (int r = 0; r < 16; ++r)
                for (int c = 0; c < 20; ++c)
                    deep[r, c] = (ushort)random.Next(4096);
            string deepPath = Path.Combine(folder, "deep.tiff");
            Tiff.Write(deepPath, deep);
            using (var options = new FlatlineOptions { SourceImageBits = 12 })
            using (var source = FrameSource.Images(new[] { deepPath }, null, options))
            {
                source.Start();
                var frame = source.Take();
                Assert.Equal(PixelFormat.Mono12, frame.Format);
                Assert.Null(frame.Pixels8);
                Assert.Equal(deep, frame.Pixels16);
                Assert.Equal(40, frame.StrideBytes);
            }
        }

        [Fact]
        public void HostEncoderPositionsTravelWithTheFrames()
        {
            using var calib = SmallSensor();
            using var line = Line(calib);
            using var auto = FrameSource.Simulator(line);
            // Only encoder mode Host takes positions from the host.
            Assert.Throws<FlatlineStateException>(() => auto.SetEncoder(1.0));
            using var options = new FlatlineOptions { SourceEncoderMode = EncoderMode.Host };
            using var source = FrameSource.Simulator(line, options);
            source.Start();
            Assert.True(double.IsNaN(source.Take().EncoderMm));   // before the first SetEncoder
            source.SetEncoder(12.5);
            Assert.Equal(12.5, source.Take().EncoderMm);
            Assert.Equal(12.5, source.Take().EncoderMm);           // the value set last
            source.SetEncoder(20.0);
            Assert.Equal(20.0, source.Take().EncoderMm);
            Assert.Throws<InvalidArgumentException>(() => source.SetEncoder(double.NaN));
            Assert.Equal(20.0, source.Take().EncoderMm);           // unchanged by the refused call
        }

        [Fact]
        public void ACameraLeftStreamingByADeadProcessIsRecoveredOnOpen()
        {
            using var bus = new U3VSimBus();
            bus.AddCamera("Flatline", "Orphan", "O", 64, 16);
            bus.Set(0, U3VSimParam.LeftStreaming, 1);
            Assert.Equal(1UL, bus.Get(0, U3VSimParam.Acquiring));
            using var camera = FrameSource.U3V("O", null, bus);
            Assert.Equal(0UL, bus.Get(0, U3VSimParam.Acquiring));  // stopped on open
            Assert.Equal(0UL, bus.Get(0, U3VSimParam.SiControl));
            Assert.Equal(1UL, camera.Count(SourceCounter.StreamRecoveries));
            camera.Start();
            Assert.Equal(64, camera.Take(1000).Width);
            Assert.Equal(0UL, camera.Count(SourceCounter.Dropped));  // the half-sent frame is not delivered
        }

        [Fact]
        public void AStopTheCameraDidNotTakeSaysSoAndStartRecovers()
        {
            using var bus = new U3VSimBus();
            bus.AddCamera("Flatline", "Faulty", "F", 64, 16);
            using var camera = FrameSource.U3V("F", null, bus);
            camera.Start();
            Assert.Equal(64, camera.Take(1000).Width);
            // Every command of the stop is lost: 3 rounds x 3 attempts x 2 steps.
            bus.Inject(0, U3VFault.ControlTimeout, 0, 18);
            var e = Assert.Throws<DeviceTimeoutException>(() => camera.Stop());
            Assert.Contains("may still be streaming", e.Message);
            Assert.Equal(1UL, bus.Get(0, U3VSimParam.SiControl));  // really streaming on
            Assert.Equal(0UL, bus.Get(0, U3VSimParam.FaultsPending));
            camera.Start();                                          // stops it first
            Assert.Equal(1UL, camera.Count(SourceCounter.StreamRecoveries));
            Assert.Equal(64, camera.Take(1000).Width);
            camera.Stop();
            Assert.Equal(0UL, bus.Get(0, U3VSimParam.SiControl));
            Assert.Equal(0UL, bus.Get(0, U3VSimParam.Acquiring));
        }

        [Fact]
        public void ImageErrorsMapToTheirExceptions()
        {
            var image = new byte[8, 8];
            string path = Path.Combine(folder, "a.png.tif");
            Tiff.Write(path, image);
            string csv = Path.Combine(folder, "short.csv");
            File.WriteAllText(csv, "1.0\n2.0\n");   // two rows for one image
            var format = Assert.Throws<FlatlineFormatException>(() => FrameSource.Images(new[] { path }, csv));
            Assert.Equal(Status.Format, format.Status);
            output.WriteLine(format.Message);
            var io = Assert.Throws<FlatlineIOException>(() => FrameSource.Images(new[] { Path.Combine(folder, "none.png") }));
            Assert.Equal(Status.IO, io.Status);
            Assert.IsType<FlatlineIOException>(io);    // not the Format subclass
            string empty = Path.Combine(folder, "empty");
            Directory.CreateDirectory(empty);
            Assert.Equal(Status.NotFound,
                         Assert.Throws<NotFoundException>(() => FrameSource.ImageDirectory(empty)).Status);
            Assert.Throws<ArgumentException>(() => FrameSource.Images(Array.Empty<string>()));
            Assert.Throws<ArgumentNullException>(() => FrameSource.Images(new string[] { null! }));  // a null path on purpose: the check under test
        }

        [Fact]
        public void ASimulatedCameraIsListedOpenedAndControlledThroughItsFeatures()
        {
            using var bus = new U3VSimBus();
            Assert.Equal(0, bus.AddCamera("Flatline", "TestCam", "SN-1", 64, 32));
            Assert.Equal(1, bus.AddCamera("Flatline", "TestCam", "SN-2", 96, 40));
            var cameras = FrameSource.Cameras(bus);
            Assert.Equal(2, cameras.Count);          // the bus's non-camera device is skipped
            Assert.Equal("SN-2", cameras[1].Serial);
            Assert.Equal("TestCam", cameras[1].Model);
            Assert.Equal("Flatline", cameras[0].Vendor);
            Assert.Equal(5000, cameras[0].SpeedMbps);
            Assert.Throws<NotFoundException>(() => FrameSource.U3V("SN-9", null, bus));
            using var camera = FrameSource.U3V("SN-2", null, bus);
            Assert.Equal(SourceKind.U3V, camera.Kind);
            Assert.Same(bus, camera.Parent);
            Assert.Equal("SN-2", camera.GetCameraString(CameraString.Serial));
            Assert.Equal(5000UL, camera.GetCameraValue(CameraValue.SpeedMbps));
            Assert.Equal(1UL, bus.Get(1, U3VSimParam.Open));
            Assert.Equal(96, camera.GetInt("Width"));
            Assert.Equal(40, camera.GetInt("Height"));
            camera.SetFloat("Gain", 2.5);            // a float32 register: 2.5 is exact
            Assert.Equal(2.5, camera.GetFloat("Gain"));
            // ExposureTime is a Converter of its raw register (us, FROM - 0).
            camera.SetFloat("ExposureTime", 1234.0);
            Assert.Equal(1234u, bus.Peek(1, 0x1001C));
            Assert.Equal(new byte[] { 0xD2, 0x04, 0, 0 }, camera.ReadMemory(0x1001C, 4));
            camera.WriteMemory(0x1001C, new byte[] { 0x10, 0x27, 0, 0 });
            Assert.Equal(10000, camera.GetInt("ExposureTime"));
            // A feature the camera lacks is named; mapped to a register it works.
            var missing = Assert.Throws<NotFoundException>(() => camera.GetInt("ExposureAbs"));
            Assert.Contains("ExposureAbs", missing.Message);
            camera.MapFeature("ExposureAbs", 0x1001C, 4);
            Assert.Equal(10000, camera.GetInt("ExposureAbs"));

            camera.Start();
            Assert.Equal(1UL, bus.Get(1, U3VSimParam.Acquiring));
            ulong first = 0;
            for (int f = 0; f < 3; ++f)
            {
                var frame = camera.Take(1000);
                Assert.Equal(96, frame.Width);
                Assert.Equal(40, frame.Height);
                if (f == 0)
                    first = frame.BlockId;
                ulong b = frame.BlockId;
                Assert.Equal(first + (ulong)f, b);
                // The test pattern of source.h, byte i of block b.
                for (int i = 0; i < 96 * 40; i += 37)
                    Assert.Equal((byte)(b * 131 + (ulong)i * 7 + (ulong)(i >> 9)), frame.Mono8()[i / 96, i % 96]);
                Assert.Equal(3.0 * f, frame.EncoderMm);  // fixed step, 3 mm default
            }
            camera.Stop();
            Assert.Equal(0UL, bus.Get(1, U3VSimParam.Acquiring));
            Assert.Equal(3UL, camera.Count(SourceCounter.Frames));
        }

        [Fact]
        public void InjectedCameraFaultsRaiseDeviceExceptionsAndAreCounted()
        {
            using var bus = new U3VSimBus();
            bus.AddCamera("Flatline", "Faulty", "T", 64, 16);
            bus.AddCamera("Flatline", "Faulty", "U", 64, 16);
            bus.AddCamera("Flatline", "Faulty", "S", 64, 16);
            bus.Inject(0, U3VFault.StreamTimeout, at: 2);
            bus.Inject(1, U3VFault.Unplug, at: 2);
            bus.Inject(2, U3VFault.ShortFrame, at: 2);

            using (var stalled = FrameSource.U3V("T", null, bus))
            {
                stalled.Start();
                Assert.Equal(1UL, stalled.Take(100).BlockId);   // block ids count from 1
                var timeout = Assert.Throws<DeviceTimeoutException>(() => stalled.Next(100));
                Assert.Equal(Status.Timeout, timeout.Status);
                Assert.IsAssignableFrom<DeviceException>(timeout);   // callers may catch both as device faults
                Assert.Equal(1UL, stalled.Count(SourceCounter.Timeouts));
                output.WriteLine($"timeout: {timeout.Message}");
            }
            var unplugged = FrameSource.U3V("U", null, bus);
            unplugged.Start();
            Assert.Equal(1UL, unplugged.Take(100).BlockId);
            var gone = Assert.Throws<DeviceException>(() => unplugged.Next(100));
            Assert.IsType<DeviceException>(gone);
            Assert.Equal(Status.Device, gone.Status);
            Assert.IsType<DeviceException>(Assert.ThrowsAny<DeviceException>(() => unplugged.Next(100)));  // and later
            Assert.Equal(1UL, unplugged.Count(SourceCounter.Disconnects));
            output.WriteLine($"unplugged: {gone.Message}");
            unplugged.Dispose();   // still works

            using (var shortFrames = FrameSource.U3V("S", null, bus))
            {
                shortFrames.Start();
                Assert.Equal(1UL, shortFrames.Take(100).BlockId);
                Assert.Equal(3UL, shortFrames.Take(100).BlockId);   // block 2 dropped, the next delivered
                Assert.Equal(1UL, shortFrames.Count(SourceCounter.Dropped));
                Assert.Equal(1UL, shortFrames.Count(SourceCounter.Short));
                Assert.NotEqual("", shortFrames.StreamError);
                output.WriteLine($"short frame: {shortFrames.StreamError}");
            }
        }

        [Fact]
        public void CameraFramesThroughExtractorAndReconstructorEqualTheDirectPathBitwise()
        {
            // As tests/c/test_u3v_loop.c: two simulators of one seed render
            // the same bytes; the camera path carries the encoder count as a
            // chunk of 0.5 mm per count (exact in binary, like the 3 mm
            // frame spacing). Tolerance 0: any difference is a byte lost,
            // reordered or mislabelled on the way.
            const int Frames = 60, Fibers = 101;
            using var calib = Calibration.Reference(firstRow: 892, rows: 256, firstXMm: -1000, pitchMm: 20,
                                                    fibers: Fibers);
            SimulatedLine MakeLine()
            {
                var line = new SimulatedLine(calib);
                line.AddDefect(DefectKind.CentreBuckle, 6, 1800);
                line.AddDefect(DefectKind.WavyEdgeBoth, 4, 1200);
                return line;
            }
            using var directLine = MakeLine();
            using var bus = new U3VSimBus();
            int cam = bus.AddCamera("Flatline", "Loop", "LOOP-1", 64, 64);
            bus.SetFrames(cam, MakeLine());
            bus.Set(cam, U3VSimParam.EncoderChunk, 1);
            bus.Set(cam, U3VSimParam.EncoderMmPerCountUm, 500);
            using var options = new FlatlineOptions
            {
                SourceEncoderMode = EncoderMode.Chunk, SourceEncoderMmPerCount = 0.5,
            };
            using var source = FrameSource.U3V("LOOP-1", options, bus);
            source.Start();
            using var exDirect = new Extractor(calib);
            using var exCamera = new Extractor(calib);
            using var rcDirect = new Reconstructor(Fibers);
            using var rcCamera = new Reconstructor(Fibers);
            Frame? frame = null;
            int valid = 0;
            for (int f = 0; f < Frames; ++f)
            {
                var expected = directLine.NextFrame();
                frame = source.Take(1000, frame);
                Assert.Equal(expected.EncoderMm, frame.EncoderMm);
                Assert.True(SameBytes(expected.Mono8(), frame.Mono8()), $"frame {f} differs");
                var a = exDirect.Process(expected);
                var b = exCamera.Process(frame.Mono8(), frame.EncoderMm);
                Assert.Equal(a.S, b.S);
                Assert.Equal(a.Valid, b.Valid);
                Assert.Equal(a.Height, b.Height);
                Assert.Equal(a.Slope, b.Slope);
                foreach (bool v in a.Valid)
                    valid += v ? 1 : 0;
                rcDirect.Push(a.S, a.Height, a.Slope, a.Valid);
                rcCamera.Push(b.S, b.Height, b.Slope, b.Valid);
            }
            // Not vacuous: most fibers carry a profile.
            Assert.True(valid > 0.9 * Frames * Fibers, $"{valid} valid samples");
            rcDirect.EndSheet();
            rcCamera.EndSheet();
            var ra = rcDirect.Pull();
            var rb = rcCamera.Pull();
            Assert.Equal(Frames, ra.Rows);
            Assert.Equal(ra.S, rb.S);
            Assert.Equal(ra.Z, rb.Z);
            Assert.Equal(0UL, source.Count(SourceCounter.Dropped));
            output.WriteLine($"{Frames} camera frames -> {ra.Rows} rows x {Fibers} fibers equal to the direct path; " +
                             $"{valid} valid samples");
        }

        [MethodImpl(MethodImplOptions.NoInlining)]
        private static FrameSource SourceOwningTheOnlyReference(Calibration calib, out WeakReference line)
        {
            var owned = Line(calib);
            line = new WeakReference(owned);
            return FrameSource.Simulator(owned);
        }

        private static void CollectEverything()
        {
            for (int i = 0; i < 3; ++i)
            {
                GC.Collect();
                GC.WaitForPendingFinalizers();
            }
        }

        [Fact]
        public void ASourceKeepsItsLineAndItsBusAlive()
        {
            using var calib = SmallSensor();
            using (var source = SourceOwningTheOnlyReference(calib, out WeakReference line))
            {
                CollectEverything();
                Assert.True(line.IsAlive, "the line was collected while its source lives");
                source.Start();
                Assert.Equal(5.0, Skip(source, 1).EncoderMm);
                // Disposing the line first only defers its native destroy.
                Assert.IsType<SimulatedLine>(line.Target).Dispose();
                Assert.Equal(10.0, source.Take().EncoderMm);
            }

            Finalizers.Settle();
            long busesBefore = U3VSimHandle.Live, linesBefore = SimHandle.Live;
            var bus = new U3VSimBus();
            bus.AddCamera("Flatline", "Held", "H", 64, 16);
            var renderer = Line(calib);
            bus.SetFrames(0, renderer);
            int width = renderer.FrameWidth, height = renderer.FrameHeight;
            var camera = FrameSource.U3V("H", null, bus);
            bus.Dispose();            // the source still holds the bus,
            renderer.Dispose();       // and the bus the line
            Assert.Throws<ObjectDisposedException>(() => bus.AddCamera("a", "b", "c", 64, 16));
            Assert.Equal(busesBefore + 1, U3VSimHandle.Live);
            Assert.Equal(linesBefore + 1, SimHandle.Live);
            camera.Start();
            var frame = camera.Take(1000);
            Assert.Equal(width, frame.Width);    // the line's frame size
            Assert.Equal(height, frame.Height);
            Assert.Equal(128, height);
            camera.Dispose();         // the last holder: everything goes now
            Assert.Equal(busesBefore, U3VSimHandle.Live);
            Assert.Equal(linesBefore, SimHandle.Live);
        }

        private static Frame Skip(FrameSource source, int frames)
        {
            for (int i = 0; i < frames; ++i)
                source.Next();
            return source.Take();
        }

        [Fact]
        public void DisposeIsImmediateIdempotentAndFinal()
        {
            using var bus = new U3VSimBus();
            bus.AddCamera("Flatline", "D", "D", 64, 16);
            Finalizers.Settle();
            long before = SourceHandle.Live;
            var source = FrameSource.U3V(null, null, bus);   // the first camera
            Assert.Equal(before + 1, SourceHandle.Live);
            Assert.Equal(1UL, bus.Get(0, U3VSimParam.Open));
            source.Start();
            source.Dispose();
            Assert.Equal(before, SourceHandle.Live);
            Assert.Equal(0UL, bus.Get(0, U3VSimParam.Open));       // released
            Assert.Equal(0UL, bus.Get(0, U3VSimParam.Acquiring));  // and stopped
            source.Dispose();
            Assert.Throws<ObjectDisposedException>(() => source.Next());
            Assert.Throws<ObjectDisposedException>(() => source.Start());
            Assert.Throws<ObjectDisposedException>(() => source.Count(SourceCounter.Frames));
            bus.Dispose();
            bus.Dispose();
            Assert.Throws<ObjectDisposedException>(() => bus.Get(0, U3VSimParam.Open));
        }
    }
}
