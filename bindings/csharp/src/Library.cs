// SPDX-License-Identifier: Apache-2.0
using System;

namespace Flatline
{
    /// <summary>
    /// Library-wide entry points: version, native library location, and the
    /// one-call batch reconstruction.
    /// </summary>
    /// <remarks>
    /// These live on <c>Library</c> rather than on a class named
    /// <c>Flatline</c>: a type named like its namespace is shadowed by the
    /// namespace in consumer code (<c>Flatline.Reconstruct</c> would look for a
    /// type <c>Reconstruct</c> in namespace <c>Flatline</c>).
    /// </remarks>
    public static class Library
    {
        static Library() => NativeLoader.EnsureLoaded();

        /// <summary>The native library's version number,
        /// MAJOR * 10000 + MINOR * 100 + PATCH.</summary>
        public static int Version => FlatlineNative.flt_version();

        /// <summary>The native library's "MAJOR.MINOR.PATCH".</summary>
        public static string VersionString => FlatlineNative.flt_version_string();

        /// <summary>The version of the C headers this binding was generated from.</summary>
        public static int BindingVersion => FlatlineNative.FLT_VERSION_NUMBER;

        /// <summary>
        /// Where to load the native glue library from, instead of the default
        /// .NET probing (application folder, runtimes/&lt;rid&gt;/native): a
        /// folder holding libflatline_csharp.so / flatline_csharp.dll (and
        /// libflatline.so.0 / libflatline.dll beside it), or the glue file
        /// itself. Set it before the first call into the library; the
        /// environment variable FLATLINE_NATIVE_PATH does the same when this
        /// is null. Setting it after the library is loaded throws
        /// <see cref="InvalidOperationException"/>.
        /// </summary>
        public static string? NativeLibraryPath
        {
            get => NativeLoader.ConfiguredPath;
            set => NativeLoader.ConfiguredPath = value;
        }

        /// <summary>The C enumerator name of a status, e.g. "FLT_ERR_STATE".</summary>
        public static string StatusName(Status status) => FlatlineNative.flt_status_string((int)status);

        /// <summary>
        /// Frees the working memory <see cref="Reconstruct"/> and
        /// <c>ReconstructFlagged</c> keep for the next call of a sheet of the
        /// same shape (a loop of calls allocates nothing after the first; up to
        /// 4 shapes and 256 MB stay kept until this call or the end of the
        /// process): after a one-off sheet much larger than the usual ones, or
        /// before a long idle time. Returns the bytes freed (as recon.h's
        /// "Memory" formula counts them).
        /// </summary>
        public static double ReleaseReconstructMemory()
        {
            FlatlineNative.flt_reconstruct_release(out double bytes);
            return bytes;
        }

        /// <summary>
        /// Reconstructs one whole sheet in one call: the least-squares spline
        /// of all rows at once (no lag, no carry-over). Shapes as in
        /// <see cref="Reconstructor.Push(double[], double[,], double[,], bool[,])"/>:
        /// <paramref name="s"/> [rows], the others [rows, fibers] (row-major:
        /// rows along travel, fibers across the width).
        /// </summary>
        public static unsafe ReconResult Reconstruct(double[] s, double[,] height, double[,] slope,
                                                     bool[,]? valid = null, FlatlineOptions? options = null)
        {
            int rows = Shapes.Rows(s, nameof(s));
            int fibers = Shapes.Columns(height, nameof(height));
            if (fibers < 1)
                throw new ArgumentException("height has no fibers (second dimension is 0)", nameof(height));
            Shapes.Check(height, rows, fibers, nameof(height));
            Shapes.Check(slope, rows, fibers, nameof(slope));
            if (valid != null)
                Shapes.Check(valid, rows, fibers, nameof(valid));
            var z = new double[rows, fibers];
            var flags = new byte[rows, fibers];
            using (var scope = FlatlineOptions.Borrow(options))
            {
                fixed (double* ps = s, ph = height, pg = slope, pz = z)
                fixed (bool* pv = valid)
                fixed (byte* pf = flags)
                {
                    FlatlineNative.flt_reconstruct(scope.Handle, (ulong)rows, (ulong)fibers, ps, ph, pg,
                                                   (byte*)pv, pz, pf);
                }
            }
            return new ReconResult((double[])s.Clone(), z, flags);
        }

        /// <summary>As <see cref="Reconstruct"/>, with the extractor's
        /// per-sample flags [rows, fibers] in place of a validity mask
        /// (flt_reconstruct_flagged): off-strip samples come out NaN flagged
        /// <see cref="ReconFlags.OffStrip"/>.</summary>
        public static unsafe ReconResult ReconstructFlagged(double[] s, double[,] height, double[,] slope,
                                                            ReconFlags[,] flags, FlatlineOptions? options = null)
        {
            int rows = Shapes.Rows(s, nameof(s));
            int fibers = Shapes.Columns(height, nameof(height));
            if (fibers < 1)
                throw new ArgumentException("height has no fibers (second dimension is 0)", nameof(height));
            Shapes.Check(height, rows, fibers, nameof(height));
            Shapes.Check(slope, rows, fibers, nameof(slope));
            if (flags == null)
                throw new ArgumentNullException(nameof(flags));
            Shapes.Check(flags, rows, fibers, nameof(flags));
            var z = new double[rows, fibers];
            var outFlags = new byte[rows, fibers];
            using (var scope = FlatlineOptions.Borrow(options))
            {
                fixed (double* ps = s, ph = height, pg = slope, pz = z)
                fixed (ReconFlags* pin = flags)
                fixed (byte* pf = outFlags)
                {
                    FlatlineNative.flt_reconstruct_flagged(scope.Handle, (ulong)rows, (ulong)fibers, ps, ph,
                                                           pg, (byte*)pin, pz, pf);
                }
            }
            return new ReconResult((double[])s.Clone(), z, outFlags);
        }
    }
}
