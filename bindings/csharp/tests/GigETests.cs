// SPDX-License-Identifier: Apache-2.0
using System;
using System.Diagnostics;
using System.IO;
using System.Runtime.InteropServices;
using System.Threading;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>GigE Vision from C#: aravis's fake camera
    /// (arv-fake-gv-camera-0.8, Debian package aravis-tools) started here on
    /// 127.0.0.1, found by discovery, opened by address, and its frames
    /// compared with the ramp aravis fills them with: pixel (x, y) of frame
    /// id f is (x + y + f) % 255. Linux only; skipped elsewhere or when the
    /// camera is not installed.</summary>
    public class GigETests
    {
        private const string Fake = "arv-fake-gv-camera-0.8";

        private static string? FindFake()
        {
            if (!RuntimeInformation.IsOSPlatform(OSPlatform.Linux))
                return null;
            foreach (var dir in (Environment.GetEnvironmentVariable("PATH") ?? "").Split(':'))
            {
                var path = Path.Combine(dir, Fake);
                if (dir.Length > 0 && File.Exists(path))
                    return path;
            }
            return null;
        }

        [Fact]
        public void DiscoveryAndFramesFromAravisFakeCamera()
        {
            var fake = FindFake();
            if (fake == null)
            {
                // Skipped (a message, no assertion: the same under xunit 2 and 3).
                Console.Error.WriteLine($"GigETests: {Fake} (Debian package aravis-tools, Linux) is not available");
                return;
            }
            var serial = "CS" + (Environment.ProcessId % 1000000);
            using var process = Process.Start(new ProcessStartInfo(fake!, $"-i 127.0.0.1 -s {serial}")
            {
                RedirectStandardOutput = true,
                RedirectStandardError = true,
                UseShellExecute = false,
            })!;
            try
            {
                // It answers within ~50 ms; 10 s covers a loaded machine.
                var found = FrameSource.GigECameras("127.0.0.1", 200);
                for (int i = 0; i < 50 && found.Count == 0; ++i)
                {
                    Thread.Sleep(200);
                    found = FrameSource.GigECameras("127.0.0.1", 200);
                }
                Assert.Single(found);
                if (found[0].Serial != serial)
                {
                    Console.Error.WriteLine("GigETests: another camera answers on 127.0.0.1:3956");
                    return;
                }
                Assert.Equal("Aravis", found[0].Vendor);
                Assert.Equal("Fake", found[0].Model);
                Assert.Equal("127.0.0.1", found[0].Address);

                using var source = FrameSource.GigE(found[0].Address,
                                                    new FlatlineOptions { GigeResendTimeout = 25 });
                Assert.Equal(SourceKind.GigE, source.Kind);
                Assert.Equal(serial, source.GetCameraString(CameraString.Serial));
                Assert.Equal(0x7F000001ul, source.GetCameraValue(CameraValue.IpAddress));
                source.SetInt("Width", 128);
                source.SetInt("Height", 64);
                source.SetFloat("AcquisitionFrameRate", 100.0);
                Assert.Equal(128 * 64, source.GetInt("PayloadSize"));
                source.Start();
                ulong first = 0, previous = 0;
                for (int n = 0; n < 20; ++n)
                {
                    var frame = source.Take(2000);
                    if (n == 0)
                        first = frame.BlockId;
                    else
                        Assert.True(frame.BlockId > previous, $"block {frame.BlockId} after {previous}");
                    previous = frame.BlockId;
                    ulong id = (frame.BlockId - 1) % 65535 + 1;  // the camera's 16-bit id
                    var pixels = frame.Pixels8!;
                    Assert.Equal(64, pixels.GetLength(0));
                    Assert.Equal(128, pixels.GetLength(1));
                    for (int y = 0; y < 64; ++y)
                        for (int x = 0; x < 128; ++x)
                            if (pixels[y, x] != (byte)(((ulong)(x + y) + id) % 255))
                                Assert.Fail($"frame {n}: pixel ({x}, {y}) = {pixels[y, x]}");
                }
                // Loopback loses nothing unless this process stalls long enough
                // for its socket buffer to overflow (a loaded machine): then the
                // camera (which does not resend) costs frames, each counted.
                var counters = source.Counters;
                Assert.Equal(20ul, counters[SourceCounter.Frames]);
                Assert.True(previous - first + 1 <= 20 + counters[SourceCounter.Dropped] + counters[SourceCounter.Lost],
                            $"blocks {first}..{previous}: {counters[SourceCounter.Dropped]} dropped, {counters[SourceCounter.Lost]} lost");
            }
            finally
            {
                process.Kill();
                process.WaitForExit();
            }
        }

        [Fact]
        public void BadArguments()
        {
            Assert.Throws<ArgumentOutOfRangeException>(() => FrameSource.GigECameras("127.0.0.1", 0));
            Assert.Throws<InvalidArgumentException>(() => FrameSource.GigECameras("camera.local", 10));
            Assert.Throws<DeviceTimeoutException>(() => FrameSource.GigE(
                "127.0.0.1:9", new FlatlineOptions { GigeControlTimeout = 10, GigeCommandAttempts = 1 }));
        }
    }
}
