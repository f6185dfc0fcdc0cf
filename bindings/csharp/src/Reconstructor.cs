// SPDX-License-Identifier: Apache-2.0
using System;

namespace Flatline
{
    /// <summary>Per-sample output flags (FLT_FLAG_* in flatline/recon.h);
    /// bits combine. A value is never invented silently.</summary>
    [Flags]
    public enum ReconFlags : byte
    {
        None = 0,
        /// <summary>This row's own sample of this fiber was invalid; the value
        /// is bridged from the neighbouring samples.</summary>
        InvalidInput = FlatlineNative.FLT_FLAG_INVALID_INPUT,
        /// <summary>The row lies in a run of invalid samples longer than
        /// MaxGap: the value comes from the smoothness prior alone.</summary>
        Gap = FlatlineNative.FLT_FLAG_GAP,
        /// <summary>The fiber has had no valid height since the strip began;
        /// the value is NaN.</summary>
        NoData = FlatlineNative.FLT_FLAG_NO_DATA,
        /// <summary>The fiber lies off the strip in this row (beyond its
        /// edges, or no strip under a laser): not invalid data. As input
        /// (<see cref="Extractor.FiberFlags"/>) the sample is not used; as
        /// output the value is NaN with this flag alone.</summary>
        OffStrip = FlatlineNative.FLT_FLAG_OFF_STRIP,
    }

    /// <summary>The robust modes of the reconstructor (the option "robust",
    /// flt_robust in flatline/recon.h).</summary>
    public enum RobustMode
    {
        /// <summary>Least squares (the default).</summary>
        None = NativeRobust.FLT_ROBUST_NONE,
        /// <summary>Huber's M-estimator: the one to use against the shear
        /// station's ringing and spurious laser peaks.</summary>
        Huber = NativeRobust.FLT_ROBUST_HUBER,
        /// <summary>Tukey's biweight; can lock onto a wrong level when a
        /// strip starts inside the ringing.</summary>
        Tukey = NativeRobust.FLT_ROBUST_TUKEY,
    }

    /// <summary>
    /// Reconstructed rows. <see cref="S"/>[r] is the material position of row
    /// r in mm; <see cref="Z"/>[r, k] the height of fiber k there in mm (NaN
    /// only where NoData is set); <see cref="Flags"/>[r, k] its
    /// <see cref="ReconFlags"/> bits. Arrays are [rows, fibers]: rows along
    /// travel, fibers across the width, the C library's row-major layout.
    /// </summary>
    public sealed class ReconResult
    {
        internal ReconResult(double[] s, double[,] z, byte[,] flags)
        {
            S = s;
            Z = z;
            Flags = flags;
        }

        public double[] S { get; }
        public double[,] Z { get; }
        public byte[,] Flags { get; }
        public int Rows => S.Length;
        public int Fibers => Z.GetLength(1);
        /// <summary>The flags of one sample as an enum.</summary>
        public ReconFlags FlagsAt(int row, int fiber) => (ReconFlags)Flags[row, fiber];
    }

    /// <summary>The boundary condition carried into the next sheet: the knot
    /// position (mm) and per fiber its height (mm) and slope (mm/mm).</summary>
    public sealed class ReconBoundary
    {
        internal ReconBoundary(double s, double[] height, double[] slope)
        {
            S = s;
            Height = height;
            Slope = slope;
        }

        public double S { get; }
        public double[] Height { get; }
        public double[] Slope { get; }
    }

    /// <summary>
    /// The streaming Hermite reconstructor (flt_recon): each fiber is a cubic
    /// Hermite spline z(s) fitted to the dual-laser heights and slopes.
    /// <see cref="Push(double[], double[,], double[,], bool[,])"/> takes
    /// camera rows as they arrive, <see cref="Pull()"/> returns finished rows
    /// after a fixed lag, <see cref="EndSheet"/> finishes a sheet and carries
    /// its boundary into the next one.
    /// </summary>
    /// <remarks>
    /// Not thread-safe: use one instance from one thread at a time; separate
    /// instances are independent. Dispose frees the native memory at once; a
    /// finalizer frees it otherwise.
    /// </remarks>
    public sealed class Reconstructor : IDisposable
    {
        private readonly ReconHandle handle;

        static Reconstructor() => NativeLoader.EnsureLoaded();

        /// <summary>Creates a reconstructor for <paramref name="fibers"/>
        /// fibers. <paramref name="options"/> (null for the defaults) is
        /// copied, not kept. <see cref="InvalidArgumentException"/> for
        /// fibers = 0 or inconsistent options.</summary>
        public Reconstructor(int fibers, FlatlineOptions? options = null)
        {
            if (fibers < 0)
                throw new ArgumentOutOfRangeException(nameof(fibers), fibers, "fibers must be at least 1");
            using (var scope = FlatlineOptions.Borrow(options))
            {
                FlatlineNative.flt_recon_create((ulong)fibers, scope.Handle, out handle);
            }
            Fibers = fibers;
            handle.Track(NativeBytes());
        }

        /// <summary>Creates a reconstructor for the sensor
        /// <paramref name="calibration"/> describes (finished): its fiber
        /// grid gives the fiber count and the distance between its lasers the
        /// laser spacing, which the "laser_spacing" option would otherwise
        /// leave at 100 mm. The way to create one for a real sensor.
        /// <paramref name="options"/> (null for the defaults) is copied, not
        /// kept; leave "laser_spacing" unset in it, or equal to the
        /// calibration's: a disagreement throws
        /// <see cref="InvalidArgumentException"/> naming both values.
        /// <see cref="FlatlineStateException"/> if the calibration is not
        /// finished. The calibration is only read during the call.</summary>
        public Reconstructor(Calibration calibration, FlatlineOptions? options = null)
        {
            if (calibration == null)
                throw new ArgumentNullException(nameof(calibration));
            using (var scope = FlatlineOptions.Borrow(options))
            {
                FlatlineNative.flt_recon_create_from_calib(calibration.LiveHandle, scope.Handle, out handle);
            }
            GC.KeepAlive(calibration);
            FlatlineNative.flt_recon_fibers(handle, out UIntPtr fibers);
            Fibers = checked((int)fibers.ToUInt64());
            handle.Track(NativeBytes());
        }

        /// <summary>The number of fibers.</summary>
        public int Fibers { get; }

        /// <summary>Finished rows waiting to be pulled.</summary>
        public int Ready
        {
            get
            {
                FlatlineNative.flt_recon_ready(LiveHandle, out UIntPtr ready);
                return checked((int)ready.ToUInt64());
            }
        }

        /// <summary>The effective value of an option by its C name
        /// ("knot_spacing" resolved to mm). <see cref="NotFoundException"/>
        /// for a name that is not a reconstructor option.</summary>
        public double GetOption(string name)
        {
            var live = LiveHandle;
            FlatlineNative.flt_recon_get_option(live, FlatlineOptions.Key(name), out double value);
            return value;
        }

        /// <summary>
        /// Pushes rows. <paramref name="s"/> [rows]: material position of each
        /// row, mm, strictly increasing (also across calls and sheets).
        /// <paramref name="height"/>, <paramref name="slope"/> [rows, fibers]:
        /// measured heights (mm) and slopes (mm/mm). <paramref name="valid"/>
        /// [rows, fibers] or null: false where a sample is invalid (NaN values
        /// are invalid anyway). Wrong shapes throw <see cref="ArgumentException"/>
        /// before the native call; on any failure nothing was pushed.
        /// <see cref="BufferFullException"/> when the rows do not fit in RowCapacity.
        /// </summary>
        public unsafe void Push(double[] s, double[,] height, double[,] slope, bool[,]? valid = null)
        {
            var live = LiveHandle;
            int rows = Shapes.Rows(s, nameof(s));
            Shapes.Check(height, rows, Fibers, nameof(height));
            Shapes.Check(slope, rows, Fibers, nameof(slope));
            if (valid != null)
                Shapes.Check(valid, rows, Fibers, nameof(valid));
            // bool is one byte, 0 or 1, in a .NET array: pass it as the uint8 mask.
            fixed (double* ps = s, ph = height, pg = slope)
            fixed (bool* pv = valid)
            {
                FlatlineNative.flt_recon_push(live, (ulong)rows, (ulong)Fibers, ps, ph, pg, (byte*)pv);
            }
        }

        /// <summary>Pushes one row at position <paramref name="s"/> (mm);
        /// arrays [fibers].</summary>
        public unsafe void Push(double s, double[] height, double[] slope, bool[]? valid = null)
        {
            var live = LiveHandle;
            Shapes.Check(height, Fibers, nameof(height));
            Shapes.Check(slope, Fibers, nameof(slope));
            if (valid != null)
                Shapes.Check(valid, Fibers, nameof(valid));
            fixed (double* ph = height, pg = slope)
            fixed (bool* pv = valid)
            {
                FlatlineNative.flt_recon_push(live, 1, (ulong)Fibers, &s, ph, pg, (byte*)pv);
            }
        }

        /// <summary>Pushes a block of rows with the extractor's per-fiber flags
        /// (<see cref="Extractor.FiberFlags"/>) in place of a validity mask:
        /// <see cref="ReconFlags.None"/> valid, <see cref="ReconFlags.InvalidInput"/>
        /// invalid (bridged), <see cref="ReconFlags.OffStrip"/> off the strip
        /// (not used; its rows come out NaN flagged OffStrip). Arrays
        /// [rows, fibers] as <see cref="Push(double[], double[,], double[,], bool[,])"/>;
        /// flags must not be null.</summary>
        public unsafe void PushFlagged(double[] s, double[,] height, double[,] slope, ReconFlags[,] flags)
        {
            var live = LiveHandle;
            int rows = Shapes.Rows(s, nameof(s));
            Shapes.Check(height, rows, Fibers, nameof(height));
            Shapes.Check(slope, rows, Fibers, nameof(slope));
            if (flags == null)
                throw new ArgumentNullException(nameof(flags));
            Shapes.Check(flags, rows, Fibers, nameof(flags));
            fixed (double* ps = s, ph = height, pg = slope)
            fixed (ReconFlags* pf = flags)
            {
                FlatlineNative.flt_recon_push_flagged(live, (ulong)rows, (ulong)Fibers, ps, ph, pg, (byte*)pf);
            }
        }

        /// <summary>Pushes one row at position <paramref name="s"/> (mm) with
        /// its per-fiber flags; arrays [fibers].</summary>
        public unsafe void PushFlagged(double s, double[] height, double[] slope, ReconFlags[] flags)
        {
            var live = LiveHandle;
            Shapes.Check(height, Fibers, nameof(height));
            Shapes.Check(slope, Fibers, nameof(slope));
            if (flags == null)
                throw new ArgumentNullException(nameof(flags));
            Shapes.Check(flags, Fibers, nameof(flags));
            fixed (double* ph = height, pg = slope)
            fixed (ReconFlags* pf = flags)
            {
                FlatlineNative.flt_recon_push_flagged(live, 1, (ulong)Fibers, &s, ph, pg, (byte*)pf);
            }
        }

        /// <summary>Pulls every finished row (possibly none).
        /// <see cref="FlatlineStateException"/> if nothing was pushed since
        /// create or <see cref="Reset"/>.</summary>
        public ReconResult Pull() => Pull(int.MaxValue);

        /// <summary>Pulls up to <paramref name="maxRows"/> finished rows, oldest first.</summary>
        public unsafe ReconResult Pull(int maxRows)
        {
            if (maxRows < 0)
                throw new ArgumentOutOfRangeException(nameof(maxRows), maxRows, "maxRows must not be negative");
            var live = LiveHandle;
            int rows = Math.Min(maxRows, Ready);
            var s = new double[rows];
            var z = new double[rows, Fibers];
            var flags = new byte[rows, Fibers];
            UIntPtr pulled;
            fixed (double* ps = s, pz = z)
            fixed (byte* pf = flags)
            {
                FlatlineNative.flt_recon_pull(live, (ulong)rows, (ulong)Fibers, ps, pz, pf, out pulled);
            }
            if (pulled.ToUInt64() != (ulong)rows)
                throw new FlatlineInternalException(Status.Internal,
                    $"flt_recon_pull returned {pulled} rows where {rows} were ready");
            return new ReconResult(s, z, flags);
        }

        /// <summary>Rows pushed and not finished yet (see <see cref="Peek()"/>).</summary>
        public int Pending
        {
            get
            {
                FlatlineNative.flt_recon_pending(LiveHandle, out UIntPtr pending);
                return checked((int)pending.ToUInt64());
            }
        }

        /// <summary>Every row pushed and not finished yet, as the
        /// reconstructor estimates it now (provisional values, given every row
        /// pushed so far; final only when <see cref="Pull()"/> returns the row,
        /// latency_mm of strip later). Finished rows not pulled yet are
        /// skipped; nothing Pull returns changes.
        /// <see cref="FlatlineStateException"/> if nothing was pushed since
        /// create or <see cref="Reset"/>.</summary>
        public ReconResult Peek() => Peek(int.MaxValue);

        /// <summary>Up to <paramref name="maxRows"/> of the provisional rows,
        /// oldest first (see <see cref="Peek()"/>).</summary>
        public unsafe ReconResult Peek(int maxRows)
        {
            if (maxRows < 0)
                throw new ArgumentOutOfRangeException(nameof(maxRows), maxRows, "maxRows must not be negative");
            var live = LiveHandle;
            int rows = Math.Min(maxRows, Pending);
            var s = new double[rows];
            var z = new double[rows, Fibers];
            var flags = new byte[rows, Fibers];
            UIntPtr got;
            fixed (double* ps = s, pz = z)
            fixed (byte* pf = flags)
            {
                FlatlineNative.flt_recon_peek(live, (ulong)rows, (ulong)Fibers, ps, pz, pf, out got);
            }
            if (got.ToUInt64() != (ulong)rows)
                throw new FlatlineInternalException(Status.Internal,
                    $"flt_recon_peek returned {got} rows where {rows} were pending");
            return new ReconResult(s, z, flags);
        }

        /// <summary>Finishes the current sheet: every pushed row becomes ready
        /// to pull, and the last emitted knot becomes the boundary condition
        /// of the next sheet. <see cref="FlatlineStateException"/> if no row was
        /// pushed since the last EndSheet, create or Reset.</summary>
        public void EndSheet() => FlatlineNative.flt_recon_end_sheet(LiveHandle);

        /// <summary>Starts a new strip: drops every row not pulled yet and the carry-over.</summary>
        public void Reset() => FlatlineNative.flt_recon_reset(LiveHandle);

        /// <summary>The boundary condition carried into the next sheet.
        /// <see cref="FlatlineStateException"/> before the first EndSheet of a strip.</summary>
        public unsafe ReconBoundary Boundary()
        {
            var live = LiveHandle;
            double s;
            var height = new double[Fibers];
            var slope = new double[Fibers];
            fixed (double* ph = height, pg = slope)
            {
                FlatlineNative.flt_recon_boundary(live, (ulong)Fibers, &s, ph, pg);
            }
            return new ReconBoundary(s, height, slope);
        }

        /// <summary>Frees the native reconstructor now. Further calls throw
        /// <see cref="ObjectDisposedException"/>; a second Dispose does nothing.</summary>
        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }

        private ReconHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(Reconstructor));
                return handle;
            }
        }

        /// <summary>An estimate of the native memory held (recon.h, "Memory":
        /// 9 bytes per row and fiber for the row ring, 17 in robust mode, plus
        /// the knots a row may wait), reported to the GC as memory
        /// pressure.</summary>
        private long NativeBytes()
        {
            double rows = GetOption("row_capacity");
            double lag = GetOption("lag_knots");
            double wait = 2.0 * (lag + Math.Floor(lag / 8.0) + 2.0);  // the strip's head, at most
            double s = Math.Ceiling(GetOption("laser_spacing") / GetOption("knot_spacing") - 1e-9) + 2.0;
            bool robust = GetOption("robust") != 0.0;
            double perFiber = robust
                ? 17.0 * rows + 16.0 * ((2.0 * s + 1.0) * (s + 1.0) * (wait + 2.0 * s + 8.0) + wait + 170.0)
                : 9.0 * rows + 8.0 * (4.0 * s + 3.0) * (wait + lag / 8.0 + 12.0);
            return (long)(Fibers * perFiber);
        }
    }
}
