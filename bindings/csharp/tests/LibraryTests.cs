// SPDX-License-Identifier: Apache-2.0
using System;
using System.IO;
using System.Linq;
using Xunit;

namespace Flatline.Tests
{
    public class LibraryTests
    {
        [Fact]
        public void VersionOfTheLibraryMatchesTheHeadersTheBindingWasGeneratedFrom()
        {
            Assert.Equal(Library.BindingVersion, Library.Version);
            string[] parts = Library.VersionString.Split('.');
            Assert.Equal(3, parts.Length);
            int number = int.Parse(parts[0]) * 10000 + int.Parse(parts[1]) * 100 + int.Parse(parts[2]);
            Assert.Equal(Library.Version, number);
        }

        /// <summary>The native files sit beside the managed assemblies (the
        /// application folder, as a published program has them). On a
        /// case-insensitive file system (Windows) no native file may share a
        /// name with a managed one: a core library named flatline.dll *is*
        /// the managed Flatline.dll there (one overwrote the other, and the
        /// glue's import bound to the managed file: EntryPointNotFound).</summary>
        [Fact]
        public void NativeFilesDoNotCollideWithManagedAssemblies()
        {
            string folder = AppContext.BaseDirectory;
            // The SONAME: libflatline.so.0.MINOR while MAJOR is 0, else libflatline.so.MAJOR.
            int version = Library.Version, major = version / 10000, minor = version / 100 % 100;
            string soname = major == 0 ? $"libflatline.so.0.{minor}" : $"libflatline.so.{major}";
            string core = OperatingSystem.IsWindows() ? "libflatline.dll" : soname;
            string glue = NativeLoader.PlatformFileName(NativeLoader.GlueName);
            Assert.True(File.Exists(Path.Combine(folder, core)), $"{core} is beside the program");
            Assert.True(File.Exists(Path.Combine(folder, glue)), $"{glue} is beside the program");
            Assert.True(File.Exists(Path.Combine(folder, "Flatline.dll")), "the managed assembly too");
            var managed = AppDomain.CurrentDomain.GetAssemblies()
                .Select(a => a.GetName().Name + ".dll").ToList();
            Assert.Contains("Flatline.dll", managed);
            foreach (string native in new[] { core, glue, NativeLoader.WindowsCoreFile })
                Assert.DoesNotContain(managed, m => string.Equals(m, native, StringComparison.OrdinalIgnoreCase));
            // The whole chain binds: managed Flatline -> glue -> core.
            Assert.Equal(Library.BindingVersion, Library.Version);
        }

        /// <summary>The working memory a batch call keeps is freed and
        /// counted (at least the 20 x 8 bytes per fiber and knot recon.h
        /// gives, halved for its "about"), and the next call works. (That
        /// none is left after it, the Python and C suites check: here other
        /// test classes may run batch calls at the same time.)</summary>
        [Fact]
        public void ReleaseReconstructMemoryFreesWhatABatchCallKept()
        {
            const int rows = 400, fibers = 50;
            var s = new double[rows];
            var height = new double[rows, fibers];
            var slope = new double[rows, fibers];
            for (int r = 0; r < rows; ++r)
                s[r] = 3.0 * r;
            Library.Reconstruct(s, height, slope);
            double knots = (s[rows - 1] - s[0] + 100.0) / 100.0 + 4;
            double freed = Library.ReleaseReconstructMemory();
            Assert.True(freed >= 10.0 * 8.0 * knots * fibers, $"freed {freed} bytes");
            ReconResult again = Library.Reconstruct(s, height, slope);
            Assert.Equal(0.0, again.Z[0, 0], 9);
        }

        [Fact]
        public void StatusNamesComeFromTheCLibrary()
        {
            Assert.Equal("FLT_OK", Library.StatusName(Status.Ok));
            Assert.Equal("FLT_ERR_INVALID_ARGUMENT", Library.StatusName(Status.InvalidArgument));
            Assert.Equal("FLT_ERR_BUFFER_FULL", Library.StatusName(Status.BufferFull));
            Assert.Equal("FLT_ERR_UNKNOWN", Library.StatusName((Status)(-1234)));
        }

        [Fact]
        public void NativeLibraryPathCannotChangeOnceTheLibraryIsLoaded()
        {
            Assert.True(Library.Version > 0);  // loads the library
            var error = Assert.Throws<InvalidOperationException>(() => Library.NativeLibraryPath = "/nowhere");
            Assert.Contains("before the first call", error.Message);
            Assert.Null(Library.NativeLibraryPath);
        }

        [Fact]
        public void NativePathOverrideNamesAFolderOrTheFileItself()
        {
            string folder = AppContext.BaseDirectory;
            string glue = NativeLoader.PlatformFileName("flatline_csharp");
            Assert.Equal(OperatingSystem.IsWindows() ? "flatline_csharp.dll" : "libflatline_csharp.so", glue);
            Assert.Equal(Path.Combine(Path.GetFullPath(folder), glue), NativeLoader.ResolveOverride(folder));
            string file = Path.Combine(folder, glue);
            Assert.True(File.Exists(file), "the glue is copied beside the tests, where .NET probes it");
            Assert.Equal(file, NativeLoader.ResolveOverride(file));
            Assert.Null(NativeLoader.ResolveOverride(null));
            Assert.Null(NativeLoader.ResolveOverride(""));
        }

        [Fact]
        public void BatchReconstructReturnsEveryRowWithItsPosition()
        {
            var sheet = Sheet.Measure(Sheet.Waves, 400, 3, 1000.0, 7.5);
            var result = Library.Reconstruct(sheet.S, sheet.Height, sheet.Slope);
            Assert.Equal(400, result.Rows);
            Assert.Equal(3, result.Fibers);
            Assert.Equal(sheet.S, result.S);
            Assert.NotSame(sheet.S, result.S);
            Assert.True(Sheet.MaxError(result.Z, sheet.TrueZ) < 0.01);
            Assert.All(Enumerable.Range(0, 400), r => Assert.Equal(ReconFlags.None, result.FlagsAt(r, 1)));
        }

        [Fact]
        public void BatchReconstructChecksShapesBeforeTheNativeCall()
        {
            var sheet = Sheet.Measure(Sheet.Waves, 20, 3, 0.0, 10.0);
            var e = Assert.Throws<ArgumentException>(() =>
                Library.Reconstruct(sheet.S, sheet.Height, new double[20, 2]));
            Assert.Equal("slope", e.ParamName);
            e = Assert.Throws<ArgumentException>(() =>
                Library.Reconstruct(sheet.S, new double[19, 3], sheet.Slope));
            Assert.Equal("height", e.ParamName);
            e = Assert.Throws<ArgumentException>(() =>
                Library.Reconstruct(sheet.S, sheet.Height, sheet.Slope, new bool[20, 4]));
            Assert.Equal("valid", e.ParamName);
            Assert.Throws<ArgumentNullException>(() => Library.Reconstruct(null!, sheet.Height, sheet.Slope));  // null on purpose: the check under test
            // Positions are the C library's business: an InvalidArgumentException
            // (an ArgumentException whose message names the position).
            var s = (double[])sheet.S.Clone();
            s[5] = s[4];
            var invalid = Assert.Throws<InvalidArgumentException>(() => Library.Reconstruct(s, sheet.Height, sheet.Slope));
            Assert.Contains("s[5]", invalid.Message);
        }
    }
}
