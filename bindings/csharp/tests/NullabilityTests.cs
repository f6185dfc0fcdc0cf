// SPDX-License-Identifier: Apache-2.0
using System;
using System.Linq;
using System.Reflection;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>The nullable annotations of the public API say the truth:
    /// a null where a parameter is non-null throws ArgumentNullException
    /// naming that parameter (before any native call), and the parameters
    /// documented to take null are annotated so.</summary>
    public class NullabilityTests
    {
        // Every null! below is on purpose: a caller without nullable
        // checking (or one who silenced it) passes null, and the binding
        // must answer with ArgumentNullException, not a crash.

        [Fact]
        public void ANullWhereTheApiSaysNonNullNamesTheParameter()
        {
            var s = new[] { 0.0, 5.0 };
            var grid = new double[2, 3];
            Assert.Throws<ArgumentNullException>("calibration", () => new Reconstructor((Calibration)null!));
            Assert.Throws<ArgumentNullException>("s", () => Library.Reconstruct(null!, grid, grid));
            Assert.Throws<ArgumentNullException>("slope", () => Library.Reconstruct(s, grid, null!));
            using (var recon = new Reconstructor(3))
            {
                Assert.Throws<ArgumentNullException>("height", () => recon.Push(s, null!, grid));
                Assert.Throws<ArgumentNullException>("flags", () => recon.PushFlagged(s, grid, grid, null!));
                Assert.Throws<ArgumentNullException>("name", () => recon.GetOption(null!));
                Assert.Equal(0, recon.Ready);  // nothing reached the reconstructor
            }
            using (var options = new FlatlineOptions())
            {
                Assert.Throws<ArgumentNullException>("name", () => options.Set(null!, 1.0));
                Assert.Throws<ArgumentNullException>("name", () => options[null!]);
            }
            Assert.Throws<ArgumentNullException>("path", () => Calibration.Load(null!));
            Assert.Throws<ArgumentNullException>("text", () => Calibration.Parse(null!));
            Assert.Throws<ArgumentNullException>("calibration", () => new Extractor(null!));
            Assert.Throws<ArgumentNullException>("fiberX", () => new Flatness((double[])null!));
            Assert.Throws<ArgumentNullException>("calibration", () => new Gauge(null!));
            Assert.Throws<ArgumentNullException>("line", () => FrameSource.Simulator(null!));
            Assert.Throws<ArgumentNullException>("directory", () => FrameSource.ImageDirectory(null!));
            Assert.Throws<ArgumentNullException>("paths", () => FrameSource.Images(null!));
            using (var calib = Calibration.Reference(firstRow: 960, rows: 128, fibers: 11))
            {
                using var extractor = new Extractor(calib);
                Assert.Throws<ArgumentNullException>("frame", () => extractor.Process((byte[,])null!, 0.0));
                Assert.Throws<ArgumentNullException>("frame", () => extractor.Process((SimulatedFrame)null!));
                using var line = new SimulatedLine(calib);
                Assert.Throws<ArgumentNullException>("pixels", () => line.NextFrame((byte[,])null!));
                Assert.Throws<ArgumentNullException>("encoderMm", () => line.StripEdges(null!));
                using var flatness = new Flatness(calib);
                Assert.Throws<ArgumentNullException>("s", () => flatness.Evaluate(null!, new double[2, 11]));
            }
        }

        [Fact]
        public void TheParametersThatTakeNullAreAnnotatedNullable()
        {
            var context = new NullabilityInfoContext();
            var methods = typeof(Reconstructor).Assembly.GetExportedTypes()
                .SelectMany(t => t.GetMethods(BindingFlags.Public | BindingFlags.Instance | BindingFlags.Static |
                                              BindingFlags.DeclaredOnly).Cast<MethodBase>()
                                 .Concat(t.GetConstructors()))
                .ToList();
            // Every options bag is optional (null: the defaults).
            var options = methods.SelectMany(m => m.GetParameters())
                .Where(p => p.ParameterType == typeof(FlatlineOptions)).ToList();
            Assert.True(options.Count >= 15, $"{options.Count} options parameters");
            foreach (var p in options)
                Assert.True(context.Create(p).WriteState == NullabilityState.Nullable,
                            $"{p.Member.DeclaringType?.Name}.{p.Member.Name}({p.Name}) is not FlatlineOptions?");
            // A few of the others that take null, by name.
            ParameterInfo Parameter(Type type, string method, string name) =>
                methods.Where(m => m.DeclaringType == type && m.Name == method)
                       .SelectMany(m => m.GetParameters()).First(p => p.Name == name);
            foreach (var p in new[]
                     {
                         Parameter(typeof(FrameSource), nameof(FrameSource.U3V), "serial"),
                         Parameter(typeof(FrameSource), nameof(FrameSource.U3V), "bus"),
                         Parameter(typeof(FrameSource), nameof(FrameSource.Cameras), "bus"),
                         Parameter(typeof(FrameSource), nameof(FrameSource.Images), "encoderCsv"),
                         Parameter(typeof(FrameSource), nameof(FrameSource.Next), "reuse"),
                         Parameter(typeof(SimulatedLine), ".ctor", "calibration"),
                         Parameter(typeof(Reconstructor), nameof(Reconstructor.Push), "valid"),
                         Parameter(typeof(Gauge), nameof(Gauge.Attach), "source"),
                     })
                Assert.True(context.Create(p).WriteState == NullabilityState.Nullable,
                            $"{p.Member.DeclaringType?.Name}.{p.Member.Name}({p.Name}) takes null");
            // ... and those that must not be null are not.
            foreach (var p in new[]
                     {
                         Parameter(typeof(Reconstructor), ".ctor", "calibration"),
                         Parameter(typeof(Reconstructor), nameof(Reconstructor.Push), "height"),
                         Parameter(typeof(FrameSource), nameof(FrameSource.Simulator), "line"),
                     })
                Assert.True(context.Create(p).WriteState == NullabilityState.NotNull,
                            $"{p.Member.DeclaringType?.Name}.{p.Member.Name}({p.Name}) must not be null");
            // Returns that can be null say so.
            NullabilityState Returns(Type type, string method) =>
                context.Create(Assert.Single(methods.OfType<MethodInfo>(),
                                             m => m.DeclaringType == type && m.Name == method).ReturnParameter).ReadState;
            NullabilityState Property(Type type, string property) =>
                context.Create(Assert.Single(type.GetProperties(), p => p.Name == property)).ReadState;
            Assert.Equal(NullabilityState.Nullable, Returns(typeof(FrameSource), nameof(FrameSource.Next)));
            Assert.Equal(NullabilityState.Nullable, Returns(typeof(Gauge), nameof(Gauge.NextSheet)));
            Assert.Equal(NullabilityState.Nullable, Property(typeof(Frame), nameof(Frame.Pixels8)));
            Assert.Equal(NullabilityState.Nullable, Property(typeof(SimulatedFrame), nameof(SimulatedFrame.Pixels16)));
            Assert.Equal(NullabilityState.NotNull, Property(typeof(Frame), nameof(Frame.Pixels)));
            Assert.Equal(NullabilityState.NotNull, Property(typeof(Calibration), nameof(Calibration.FiberGrid)));
        }
    }
}
