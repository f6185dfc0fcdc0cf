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
    }
}
