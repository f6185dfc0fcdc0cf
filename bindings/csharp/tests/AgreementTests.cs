// SPDX-License-Identifier: Apache-2.0
using System;
using System.IO;
using System.Reflection;
using System.Runtime.InteropServices;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>
    /// The reference: libflatline's C API called directly (no SWIG glue, no
    /// binding code), with flat row-major arrays indexed by hand
    /// (element [r * fibers + k], as flatline/common.h defines).
    /// </summary>
    internal static unsafe partial class CReference
    {
        private const string Core = "flatline_core_reference";

        static CReference()
        {
            // The core library is beside the tests with its SONAME file name.
            NativeLibrary.SetDllImportResolver(typeof(CReference).Assembly, (name, assembly, path) =>
            {
                if (name != Core)
                    return IntPtr.Zero;
                // The SONAME: libflatline.so.0.MINOR while MAJOR is 0, else libflatline.so.MAJOR.
                int version = Library.Version, major = version / 10000, minor = version / 100 % 100;
                string soname = major == 0 ? $"libflatline.so.0.{minor}" : $"libflatline.so.{major}";
                string file = OperatingSystem.IsWindows() ? "libflatline.dll" : soname;
                return NativeLibrary.Load(Path.Combine(AppContext.BaseDirectory, file));
            });
        }

        [DllImport(Core)] private static extern int flt_options_create(out IntPtr options);
        [DllImport(Core)] private static extern void flt_options_destroy(IntPtr options);
        [DllImport(Core)] private static extern int flt_options_set(IntPtr options, int key, double value);
        [DllImport(Core)] private static extern int flt_option_find(byte[] name, out int key);
        [DllImport(Core)] private static extern int flt_recon_create(UIntPtr fibers, IntPtr options, out IntPtr recon);
        [DllImport(Core)] private static extern void flt_recon_destroy(IntPtr recon);
        [DllImport(Core)] private static extern int flt_recon_push(IntPtr recon, UIntPtr rows, UIntPtr fibers,
            double* s, double* height, double* slope, byte* valid);
        [DllImport(Core)] private static extern int flt_recon_pull(IntPtr recon, UIntPtr maxRows, UIntPtr fibers,
            double* s, double* z, byte* flags, out UIntPtr rows);
        [DllImport(Core)] private static extern int flt_recon_end_sheet(IntPtr recon);
        [DllImport(Core)] private static extern int flt_reconstruct(IntPtr options, UIntPtr rows, UIntPtr fibers,
            double* s, double* height, double* slope, byte* valid, double* z, byte* flags);

        private static void Ok(int status) => Assert.Equal(0, status);

        private static IntPtr Options(int lagKnots)
        {
            Ok(flt_options_create(out IntPtr options));
            Ok(flt_option_find(System.Text.Encoding.ASCII.GetBytes("lag_knots\0"), out int key));
            Ok(flt_options_set(options, key, lagKnots));
            return options;
        }

        private static (double[] h, double[] g, byte[] v) Flatten(Sheet sheet, bool[,] valid)
        {
            int rows = sheet.Rows, fibers = sheet.Fibers;
            var h = new double[rows * fibers];
            var g = new double[rows * fibers];
            var v = new byte[rows * fibers];
            for (int r = 0; r < rows; ++r)
                for (int k = 0; k < fibers; ++k)
                {
                    h[r * fibers + k] = sheet.Height[r, k];
                    g[r * fibers + k] = sheet.Slope[r, k];
                    v[r * fibers + k] = (byte)(valid[r, k] ? 1 : 0);
                }
            return (h, g, v);
        }

        /// <summary>Streams like Sheet.Stream: push chunks, pull after each,
        /// end the sheet, pull the rest. Returns z and flags flat.</summary>
        public static (double[] s, double[] z, byte[] flags) Stream(Sheet sheet, bool[,] valid, int chunk, int lagKnots)
        {
            int rows = sheet.Rows, fibers = sheet.Fibers;
            var (h, g, v) = Flatten(sheet, valid);
            var sOut = new double[rows];
            var zOut = new double[rows * fibers];
            var fOut = new byte[rows * fibers];
            IntPtr options = Options(lagKnots);
            Ok(flt_recon_create((UIntPtr)fibers, options, out IntPtr recon));
            flt_options_destroy(options);
            int pulled = 0;
            fixed (double* ps = sheet.S, ph = h, pg = g, pso = sOut, pz = zOut)
            fixed (byte* pv = v, pf = fOut)
            {
                for (int first = 0; first < rows; first += chunk)
                {
                    int count = Math.Min(chunk, rows - first);
                    Ok(flt_recon_push(recon, (UIntPtr)count, (UIntPtr)fibers, ps + first, ph + first * fibers,
                                      pg + first * fibers, pv + first * fibers));
                    pulled += Pull(recon, rows - pulled, fibers, pso + pulled, pz + pulled * fibers,
                                   pf + pulled * fibers);
                }
                Ok(flt_recon_end_sheet(recon));
                pulled += Pull(recon, rows - pulled, fibers, pso + pulled, pz + pulled * fibers,
                               pf + pulled * fibers);
            }
            flt_recon_destroy(recon);
            Assert.Equal(rows, pulled);
            return (sOut, zOut, fOut);
        }

        private static int Pull(IntPtr recon, int maxRows, int fibers, double* s, double* z, byte* flags)
        {
            Ok(flt_recon_pull(recon, (UIntPtr)maxRows, (UIntPtr)fibers, s, z, flags, out UIntPtr got));
            return (int)got;
        }

        public static (double[] z, byte[] flags) Batch(Sheet sheet, bool[,] valid)
        {
            int rows = sheet.Rows, fibers = sheet.Fibers;
            var (h, g, v) = Flatten(sheet, valid);
            var z = new double[rows * fibers];
            var flags = new byte[rows * fibers];
            fixed (double* ps = sheet.S, ph = h, pg = g, pz = z)
            fixed (byte* pv = v, pf = flags)
            {
                Ok(flt_reconstruct(IntPtr.Zero, (UIntPtr)rows, (UIntPtr)fibers, ps, ph, pg, pv, pz, pf));
            }
            return (z, flags);
        }
    }

    public class AgreementTests
    {
        private readonly ITestOutputHelper output;
        public AgreementTests(ITestOutputHelper output) => this.output = output;

        private static (Sheet sheet, bool[,] valid) Input()
        {
            // Five fibers of different shapes under 2.5 mm of vibration, with
            // a sprinkling of invalid samples (deterministic).
            var sheet = Sheet.Measure(Sheet.Waves, 1500, 5, 250.0, 6.0, vibrationSigma: 2.5, seed: 3);
            var valid = new bool[sheet.Rows, sheet.Fibers];
            var random = new Random(4);
            for (int r = 0; r < sheet.Rows; ++r)
                for (int k = 0; k < sheet.Fibers; ++k)
                    valid[r, k] = random.NextDouble() > 0.03;
            return (sheet, valid);
        }

        private void AssertSameAsFlat(double[,] z, byte[,] flags, double[] zFlat, byte[] flagsFlat)
        {
            int rows = z.GetLength(0), fibers = z.GetLength(1);
            Assert.Equal(zFlat.Length, rows * fibers);
            int differences = 0;
            for (int r = 0; r < rows; ++r)
                for (int k = 0; k < fibers; ++k)
                {
                    if (BitConverter.DoubleToInt64Bits(z[r, k]) != BitConverter.DoubleToInt64Bits(zFlat[r * fibers + k]))
                        ++differences;
                    Assert.Equal(flagsFlat[r * fibers + k], flags[r, k]);
                }
            output.WriteLine($"{rows * fibers} samples compared with the C library: {differences} differ bitwise");
            Assert.Equal(0, differences);
        }

        [Fact]
        public void StreamedResultsEqualTheCLibraryBitwise()
        {
            var (sheet, valid) = Input();
            var (s, z, flags) = CReference.Stream(sheet, valid, 50, 16);
            using var options = new FlatlineOptions { LagKnots = 16 };
            using var recon = new Reconstructor(sheet.Fibers, options);
            var result = Sheet.Stream(recon, sheet, 50, valid);
            Assert.Equal(s, result.S);
            AssertSameAsFlat(result.Z, result.Flags, z, flags);
            // Not a vacuous comparison: some samples were invalid and flagged.
            Assert.Contains(flags, f => (f & (byte)ReconFlags.InvalidInput) != 0);
        }

        [Fact]
        public void BatchResultsEqualTheCLibraryBitwise()
        {
            var (sheet, valid) = Input();
            var (z, flags) = CReference.Batch(sheet, valid);
            var result = Library.Reconstruct(sheet.S, sheet.Height, sheet.Slope, valid);
            AssertSameAsFlat(result.Z, result.Flags, z, flags);
            // The reconstruction is a real one, not zeros agreeing with zeros:
            // under 2.5 mm of vibration it stays within 1 mm of the truth
            // (measured 0.21 mm at worst; the level averages many frames).
            double error = Sheet.MaxError(result.Z, sheet.TrueZ);
            output.WriteLine($"batch under 2.5 mm vibration: max error {error:F3} mm");
            Assert.True(error < 1.0, $"max error {error} mm");
        }
    }
}
