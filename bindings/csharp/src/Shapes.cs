// SPDX-License-Identifier: Apache-2.0
using System;

namespace Flatline
{
    /// <summary>Array shape checks, done in C# before any native call so
    /// that a wrong size is an <see cref="ArgumentException"/> naming the
    /// argument, and the C library never reads past a managed array.</summary>
    internal static class Shapes
    {
        internal static int Rows(double[] s, string name)
        {
            if (s == null)
                throw new ArgumentNullException(name);
            if (s.Length == 0)
                throw new ArgumentException($"{name} is empty: push at least one row", name);
            return s.Length;
        }

        internal static int Columns<T>(T[,] array, string name)
        {
            if (array == null)
                throw new ArgumentNullException(name);
            return array.GetLength(1);
        }

        internal static void Check<T>(T[,] array, int rows, int fibers, string name)
        {
            if (array == null)
                throw new ArgumentNullException(name);
            if (array.GetLength(0) != rows || array.GetLength(1) != fibers)
                throw new ArgumentException(
                    $"{name} is [{array.GetLength(0)}, {array.GetLength(1)}] but must be " +
                    $"[{rows}, {fibers}] (rows along travel, fibers across the width)", name);
        }

        internal static void Check<T>(T[] array, int length, string name)
        {
            if (array == null)
                throw new ArgumentNullException(name);
            if (array.Length != length)
                throw new ArgumentException(
                    $"{name} has {array.Length} elements but must have {length} (one per fiber)", name);
        }
    
        /// <summary>The point count of a [count, 2] array of (u, v) px or
        /// (x, z) mm points.</summary>
        internal static int Points(double[,] points, string name)
        {
            if (points == null)
                throw new ArgumentNullException(name);
            if (points.GetLength(1) != 2)
                throw new ArgumentException(
                    $"{name} is [{points.GetLength(0)}, {points.GetLength(1)}] but must be " +
                    "[count, 2]: one point per row, two coordinates", name);
            return points.GetLength(0);
        }

        /// <summary>A laser number, 0 or 1, checked before the native call
        /// (a negative int would reach C as a huge unsigned).</summary>
        internal static uint Laser(int laser)
        {
            if (laser < 0 || laser >= Calibration.Lasers)
                throw new ArgumentOutOfRangeException(nameof(laser), laser, "laser must be 0 or 1");
            return (uint)laser;
        }

        /// <summary>A count or size that must be at least <paramref name="min"/>.</summary>
        internal static void AtLeast(int value, int min, string name)
        {
            if (value < min)
                throw new ArgumentOutOfRangeException(name, value, $"{name} must be at least {min}");
        }
    }
}
