// SPDX-License-Identifier: Apache-2.0
using System;
using Xunit;

// The GC-stress test measures process memory: no other test may run beside it.
[assembly: Xunit.v3.Parallelization(Mode = Xunit.Sdk.ParallelMode.None)]

namespace Flatline.Tests
{
    /// <summary>Live-handle counts are process-wide: an object another test
    /// left for the finalizer can be freed in the middle of a test that
    /// counts. Settle() finalizes every such object first.</summary>
    internal static class Finalizers
    {
        public static void Settle()
        {
            GC.Collect();
            GC.WaitForPendingFinalizers();
            GC.Collect();
        }
    }

    /// <summary>Synthetic dual-laser measurements of known surfaces.</summary>
    internal sealed class Sheet
    {
        public required double[] S;
        public required double[,] Height;
        public required double[,] Slope;
        /// <summary>The surface measured; empty for rows of another origin.</summary>
        public double[,] TrueZ = new double[0, 0];
        public int Rows => S.Length;
        public int Fibers => Height.GetLength(1);

        /// <summary>
        /// What the two lasers, laserSpacing apart, measure of z(s, fiber):
        /// height = (z(s - D/2) + z(s + D/2)) / 2, slope = (z(s + D/2) - z(s - D/2)) / D,
        /// plus an optional rigid vibration common to all fibers of a row
        /// (it moves both lines, so it enters the heights only).
        /// </summary>
        public static Sheet Measure(Func<double, int, double> z, int rows, int fibers, double s0,
                                    double rowSpacing, double laserSpacing = 100.0,
                                    double vibrationSigma = 0.0, int seed = 1)
        {
            var random = new Random(seed);
            var sheet = new Sheet
            {
                S = new double[rows],
                Height = new double[rows, fibers],
                Slope = new double[rows, fibers],
                TrueZ = new double[rows, fibers],
            };
            double half = laserSpacing / 2;
            for (int r = 0; r < rows; ++r)
            {
                double s = s0 + r * rowSpacing;
                sheet.S[r] = s;
                double bounce = vibrationSigma > 0 ? vibrationSigma * Gaussian(random) : 0.0;
                for (int k = 0; k < fibers; ++k)
                {
                    double rear = z(s - half, k), front = z(s + half, k);
                    sheet.Height[r, k] = (rear + front) / 2 + bounce;
                    sheet.Slope[r, k] = (front - rear) / laserSpacing;
                    sheet.TrueZ[r, k] = z(s, k);
                }
            }
            return sheet;
        }

        /// <summary>The accuracy sine of the reference article: z = 12 sin(2 pi s / 1800) mm.</summary>
        public static double Sine(double s, int fiber) => 12.0 * Math.Sin(2 * Math.PI * s / 1800.0);

        /// <summary>Different fibers, different shapes: a transposed or
        /// shifted layout cannot go unnoticed.</summary>
        public static double Waves(double s, int fiber) =>
            (3.0 + fiber) * Math.Sin(2 * Math.PI * s / (1200.0 + 150.0 * fiber) + 0.4 * fiber) + 0.5 * fiber;

        public static double Gaussian(Random random)
        {
            double u1 = 1.0 - random.NextDouble(), u2 = random.NextDouble();
            return Math.Sqrt(-2.0 * Math.Log(u1)) * Math.Cos(2 * Math.PI * u2);
        }

        /// <summary>Rows [first, first + count) of a [rows, fibers] array.</summary>
        public static T[,] Slice<T>(T[,] array, int first, int count)
        {
            int fibers = array.GetLength(1);
            var slice = new T[count, fibers];
            for (int r = 0; r < count; ++r)
                for (int k = 0; k < fibers; ++k)
                    slice[r, k] = array[first + r, k];
            return slice;
        }

        public static T[] Slice<T>(T[] array, int first, int count)
        {
            var slice = new T[count];
            Array.Copy(array, first, slice, 0, count);
            return slice;
        }

        /// <summary>Streams a sheet through a reconstructor in chunks, pulling
        /// after every push, then ends the sheet and pulls the rest.</summary>
        public static ReconResult Stream(Reconstructor recon, Sheet sheet, int chunk, bool[,]? valid = null)
        {
            var s = new System.Collections.Generic.List<double>();
            var z = new System.Collections.Generic.List<double[]>();
            var flags = new System.Collections.Generic.List<byte[]>();
            void Collect(ReconResult result)
            {
                for (int r = 0; r < result.Rows; ++r)
                {
                    s.Add(result.S[r]);
                    var zr = new double[result.Fibers];
                    var fr = new byte[result.Fibers];
                    for (int k = 0; k < result.Fibers; ++k)
                    {
                        zr[k] = result.Z[r, k];
                        fr[k] = result.Flags[r, k];
                    }
                    z.Add(zr);
                    flags.Add(fr);
                }
            }
            for (int first = 0; first < sheet.Rows; first += chunk)
            {
                int count = Math.Min(chunk, sheet.Rows - first);
                recon.Push(Slice(sheet.S, first, count), Slice(sheet.Height, first, count),
                           Slice(sheet.Slope, first, count), valid == null ? null : Slice(valid, first, count));
                Collect(recon.Pull());
            }
            recon.EndSheet();
            Collect(recon.Pull());
            var zAll = new double[s.Count, sheet.Fibers];
            var fAll = new byte[s.Count, sheet.Fibers];
            for (int r = 0; r < s.Count; ++r)
                for (int k = 0; k < sheet.Fibers; ++k)
                {
                    zAll[r, k] = z[r][k];
                    fAll[r, k] = flags[r][k];
                }
            return new ResultCopy(s.ToArray(), zAll, fAll).ToResult();
        }

        public static double MaxError(double[,] z, double[,] truth)
        {
            double worst = 0;
            for (int r = 0; r < z.GetLength(0); ++r)
                for (int k = 0; k < z.GetLength(1); ++k)
                    worst = Math.Max(worst, Math.Abs(z[r, k] - truth[r, k]));
            return worst;
        }

        /// <summary>Asserts two arrays are equal bit for bit (NaN included).</summary>
        public static void AssertBitwise(double[,] expected, double[,] actual)
        {
            Assert.Equal(expected.GetLength(0), actual.GetLength(0));
            Assert.Equal(expected.GetLength(1), actual.GetLength(1));
            for (int r = 0; r < expected.GetLength(0); ++r)
                for (int k = 0; k < expected.GetLength(1); ++k)
                    if (BitConverter.DoubleToInt64Bits(expected[r, k]) != BitConverter.DoubleToInt64Bits(actual[r, k]))
                        Assert.Fail($"[{r}, {k}]: expected {expected[r, k]:R}, got {actual[r, k]:R}");
        }
    }

    /// <summary>ReconResult has an internal constructor; the tests see internals.</summary>
    internal readonly struct ResultCopy
    {
        private readonly double[] s;
        private readonly double[,] z;
        private readonly byte[,] flags;
        public ResultCopy(double[] s, double[,] z, byte[,] flags)
        {
            this.s = s;
            this.z = z;
            this.flags = flags;
        }
        public ReconResult ToResult() => new ReconResult(s, z, flags);
    }
}
