// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.Linq;

namespace Flatline
{
    /// <summary>
    /// A coil's identity as the mill's systems name it (flatline/coil.h):
    /// carried by every sheet of the coil, its verdicts (the nominal
    /// thickness and width choose the rule bands) and its statistics, and
    /// stored in recordings and the archive. Texts are UTF-8, at most 256
    /// bytes, without control characters (the library checks each and throws
    /// <see cref="InvalidArgumentException"/> naming it).
    /// </summary>
    public sealed class CoilInfo : IEquatable<CoilInfo>
    {
        public CoilInfo(string coilId, string order = "", string heat = "", string grade = "",
                        string customer = "", double thicknessMm = 0, double widthMm = 0,
                        IReadOnlyDictionary<string, string>? extras = null)
        {
            CoilId = coilId ?? throw new ArgumentNullException(nameof(coilId));
            Order = order ?? throw new ArgumentNullException(nameof(order));
            Heat = heat ?? throw new ArgumentNullException(nameof(heat));
            Grade = grade ?? throw new ArgumentNullException(nameof(grade));
            Customer = customer ?? throw new ArgumentNullException(nameof(customer));
            ThicknessMm = thicknessMm;
            WidthMm = widthMm;
            Extras = extras == null
                ? new Dictionary<string, string>()
                : new Dictionary<string, string>(extras.ToDictionary(kv => kv.Key, kv => kv.Value));
        }

        /// <summary>The coil's id ("4711"); never empty.</summary>
        public string CoilId { get; }
        /// <summary>The production order.</summary>
        public string Order { get; }
        /// <summary>The heat (melt).</summary>
        public string Heat { get; }
        /// <summary>The steel grade ("S355MC").</summary>
        public string Grade { get; }
        /// <summary>The customer.</summary>
        public string Customer { get; }
        /// <summary>Nominal thickness, mm (0: not given).</summary>
        public double ThicknessMm { get; }
        /// <summary>Nominal width, mm (0: not given).</summary>
        public double WidthMm { get; }
        /// <summary>Free key/value pairs (keys of ASCII letters, digits, '_', '-', '.').</summary>
        public IReadOnlyDictionary<string, string> Extras { get; }

        /// <summary>A native identity holding this one (checked by the library).</summary>
        internal CoilInfoHandle ToHandle()
        {
            NativeLoader.EnsureLoaded();
            FlatlineNative.flt_coil_info_create(CoilId, out CoilInfoHandle h);
            h.Track(0);
            try
            {
                FlatlineNative.flt_coil_info_set_text(h, (int)NativeCoilField.FLT_COIL_FIELD_ORDER, Order);
                FlatlineNative.flt_coil_info_set_text(h, (int)NativeCoilField.FLT_COIL_FIELD_HEAT, Heat);
                FlatlineNative.flt_coil_info_set_text(h, (int)NativeCoilField.FLT_COIL_FIELD_GRADE, Grade);
                FlatlineNative.flt_coil_info_set_text(h, (int)NativeCoilField.FLT_COIL_FIELD_CUSTOMER, Customer);
                FlatlineNative.flt_coil_info_set_nominal(h, ThicknessMm, WidthMm);
                foreach (var kv in Extras)
                    FlatlineNative.flt_coil_info_set_extra(h, kv.Key, kv.Value);
            }
            catch
            {
                h.Dispose();
                throw;
            }
            return h;
        }

        /// <summary>A copy of a native identity (owned or lent, by its pointer).</summary>
        internal static unsafe CoilInfo FromNative(CoilInfoHandle handle)
        {
            string Text(NativeCoilField field)
            {
                IntPtr text;
                FlatlineNative.flt_coil_info_get_text(handle, (int)field, &text);
                return Utf8.Decode(text);
            }
            double thickness, width;
            FlatlineNative.flt_coil_info_get_nominal(handle, &thickness, &width);
            FlatlineNative.flt_coil_info_extra_count(handle, out UIntPtr n);
            var extras = new Dictionary<string, string>();
            for (ulong i = 0; i < n.ToUInt64(); ++i)
            {
                IntPtr key, value;
                FlatlineNative.flt_coil_info_extra(handle, i, &key, &value);
                extras[Utf8.Decode(key)] = Utf8.Decode(value);
            }
            return new CoilInfo(Text(NativeCoilField.FLT_COIL_FIELD_ID),
                                Text(NativeCoilField.FLT_COIL_FIELD_ORDER),
                                Text(NativeCoilField.FLT_COIL_FIELD_HEAT),
                                Text(NativeCoilField.FLT_COIL_FIELD_GRADE),
                                Text(NativeCoilField.FLT_COIL_FIELD_CUSTOMER), thickness, width,
                                extras);
        }

        public bool Equals(CoilInfo? other) =>
            other != null && CoilId == other.CoilId && Order == other.Order && Heat == other.Heat &&
            Grade == other.Grade && Customer == other.Customer &&
            ThicknessMm.Equals(other.ThicknessMm) && WidthMm.Equals(other.WidthMm) &&
            Extras.Count == other.Extras.Count &&
            Extras.All(kv => other.Extras.TryGetValue(kv.Key, out var v) && v == kv.Value);

        public override bool Equals(object? obj) => Equals(obj as CoilInfo);
        public override int GetHashCode() => CoilId.GetHashCode() ^ Grade.GetHashCode();
        public override string ToString() =>
            Grade.Length > 0 ? $"coil {CoilId} ({Grade})" : $"coil {CoilId}";
    }

    /// <summary>
    /// Writes a recording (flatline/record.h): attach it to a gauge and the
    /// gauge records every row it takes, its cuts and coils; or write rows
    /// with <see cref="PushRow"/>. A killed process or a power cut loses at
    /// most about twice record_commit_interval (250 ms by default). Options:
    /// record_* (e.g. <c>new FlatlineOptions().Set("record_quantum", 1.0 / 1024)</c>).
    /// </summary>
    public sealed class Recorder : IDisposable
    {
        private readonly RecorderHandle handle;
        private readonly int fibers;

        static Recorder() => NativeLoader.EnsureLoaded();

        /// <summary>Creates the file (an existing one is refused with a
        /// <see cref="FlatlineIOException"/>).</summary>
        public Recorder(string path, Calibration calibration, FlatlineOptions? options = null)
        {
            if (path == null)
                throw new ArgumentNullException(nameof(path));
            if (calibration == null)
                throw new ArgumentNullException(nameof(calibration));
            using (var scope = FlatlineOptions.Borrow(options))
                FlatlineNative.flt_recorder_create(path, calibration.LiveHandle, scope.Handle,
                                                   out handle);
            fibers = calibration.FiberGrid.Count;
            handle.Track(0);
        }

        internal RecorderHandle LiveHandle
        {
            get
            {
                if (handle.IsDisposed)
                    throw new ObjectDisposedException(nameof(Recorder));
                return handle;
            }
        }

        /// <summary>One profile row: heights (mm) and slopes (mm/mm) per fiber,
        /// valid per fiber or null (finite values are valid).</summary>
        public unsafe void PushRow(double encoderMm, double[] height, double[] slope, bool[]? valid = null)
        {
            if (height == null)
                throw new ArgumentNullException(nameof(height));
            if (slope == null)
                throw new ArgumentNullException(nameof(slope));
            if (height.Length != fibers || slope.Length != fibers || (valid != null && valid.Length != fibers))
                throw new ArgumentException($"rows have {fibers} fibers");
            byte[]? mask = valid?.Select(v => v ? (byte)1 : (byte)0).ToArray();
            fixed (double* h = height)
            fixed (double* s = slope)
            fixed (byte* m = mask)
                FlatlineNative.flt_recorder_push_row(LiveHandle, encoderMm, (ulong)fibers, h, s, m);
        }

        /// <summary>The shear cut at <paramref name="encoderMm"/>, before the next row.</summary>
        public void Cut(double encoderMm) => FlatlineNative.flt_recorder_cut(LiveHandle, encoderMm);

        /// <summary>A coil's identity, before the next row.</summary>
        public void SetCoil(CoilInfo coil)
        {
            if (coil == null)
                throw new ArgumentNullException(nameof(coil));
            using (var h = coil.ToHandle())
                FlatlineNative.flt_recorder_set_coil(LiveHandle, h);
        }

        /// <summary>Waits until everything given so far is on the disk.</summary>
        public void Sync(int timeoutMs = 10000) =>
            FlatlineNative.flt_recorder_sync(LiveHandle, (uint)Math.Max(0, timeoutMs));

        /// <summary>Writes the raw frames kept in the ring (record_frames = ring).</summary>
        public void SaveFrames() => FlatlineNative.flt_recorder_save_frames(LiveHandle);

        /// <summary>Rows given, stored and lost, blocks, commits, bytes, samples, ...</summary>
        public unsafe IReadOnlyDictionary<string, ulong> Counters()
        {
            var names = new[] { "rows", "rows_stored", "rows_lost", "blocks", "commits", "bytes",
                                "samples", "frames", "frames_lost", "events", "writer_ns" };
            var live = LiveHandle;
            var result = new Dictionary<string, ulong>();
            for (int i = 0; i < names.Length; ++i)
            {
                ulong v;
                FlatlineNative.flt_recorder_count(live, i, &v);
                result[names[i]] = v;
            }
            return result;
        }

        /// <summary>Writes what is pending and closes the file.</summary>
        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }
    }

    /// <summary>Rows of a recording as the gauge measured them.</summary>
    public sealed class RecordedRows
    {
        internal RecordedRows(double[] encoderMm, double[] timeS, double[,] height, double[,] slope,
                              byte[,] flags)
        {
            EncoderMm = encoderMm;
            TimeS = timeS;
            Height = height;
            Slope = slope;
            Flags = flags;
        }

        /// <summary>Encoder positions, mm.</summary>
        public double[] EncoderMm { get; }
        /// <summary>Host UTC times, s since 1970.</summary>
        public double[] TimeS { get; }
        /// <summary>[rows, fibers] heights, mm (NaN where Flags is not 0).</summary>
        public double[,] Height { get; }
        /// <summary>[rows, fibers] slopes, mm/mm (NaN likewise).</summary>
        public double[,] Slope { get; }
        /// <summary>[rows, fibers] 0 valid, 1 invalid input, 8 off the strip.</summary>
        public byte[,] Flags { get; }
    }

    /// <summary>A recording opened for reading (flatline/record.h).</summary>
    public sealed class Recording : IDisposable
    {
        private readonly RecordingHandle handle;

        static Recording() => NativeLoader.EnsureLoaded();

        public Recording(string path)
        {
            if (path == null)
                throw new ArgumentNullException(nameof(path));
            FlatlineNative.flt_recording_open(path, out handle);
            handle.Track(0);
        }

        private RecordingHandle LiveHandle
        {
            get
            {
                if (handle.IsDisposed)
                    throw new ObjectDisposedException(nameof(Recording));
                return handle;
            }
        }

        private double Info(NativeRecordingValue key)
        {
            FlatlineNative.flt_recording_info(LiveHandle, (int)key, out double v);
            return v;
        }

        /// <summary>The file's format version.</summary>
        public int Version => (int)Info(NativeRecordingValue.FLT_RECORDING_VERSION_OF);
        /// <summary>Fibers per row.</summary>
        public int Fibers => (int)Info(NativeRecordingValue.FLT_RECORDING_FIBERS);
        /// <summary>Rows stored.</summary>
        public long Rows => (long)Info(NativeRecordingValue.FLT_RECORDING_ROWS);
        /// <summary>Rows the writer marked as lost.</summary>
        public long RowsLost => (long)Info(NativeRecordingValue.FLT_RECORDING_ROWS_LOST);
        /// <summary>The height quantum, mm.</summary>
        public double QuantumMm => Info(NativeRecordingValue.FLT_RECORDING_QUANTUM);

        /// <summary>The calibration the recording was made with.</summary>
        public Calibration Calibration()
        {
            FlatlineNative.flt_recording_calib(LiveHandle, out CalibHandle calib);
            return Flatline.Calibration.FromHandle(calib);
        }

        /// <summary>The options of the gauge that made the recording (every
        /// default when none were recorded): a gauge made with them and
        /// <see cref="Calibration"/> replays the recording bit for bit.</summary>
        public FlatlineOptions Options()
        {
            FlatlineNative.flt_recording_options(LiveHandle, out OptionsHandle bag);
            return new FlatlineOptions(bag);
        }

        /// <summary>Checks every block (its CRC-32, and that it decodes);
        /// throws <see cref="FlatlineFormatException"/> naming the first bad one.</summary>
        public unsafe void Verify()
        {
            ulong bad;
            FlatlineNative.flt_recording_verify(LiveHandle, &bad);
        }

        /// <summary>Stored rows [first, first + count) (clipped at the last).</summary>
        public unsafe RecordedRows ReadRows(long first = 0, long count = -1)
        {
            if (first < 0)
                throw new ArgumentOutOfRangeException(nameof(first));
            long total = Rows;
            long n = Math.Max(0, count < 0 ? total - first : Math.Min(count, total - first));
            int k = Fibers;
            var e = new double[n];
            var t = new double[n];
            var h = new double[n, k];
            var s = new double[n, k];
            var f = new byte[n, k];
            UIntPtr got;
            fixed (double* pe = e)
            fixed (double* pt = t)
            fixed (double* ph = h)
            fixed (double* ps = s)
            fixed (byte* pf = f)
                FlatlineNative.flt_recording_read_rows(LiveHandle, (ulong)first, (ulong)n, (ulong)k, pe,
                                                       pt, ph, ps, pf, out got);
            if ((long)got.ToUInt64() != n)
                throw new FlatlineFormatException(Status.Format, $"the recording holds {got} rows from {first}, not {n}");
            return new RecordedRows(e, t, h, s, f);
        }

        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }
    }

    /// <summary>
    /// The archive of measured sheets (flatline/record.h): an SQLite file,
    /// or a PostgreSQL database ("postgresql://user@host/db" or
    /// "pg:host=... dbname=..."; needs a PostgreSQL client's libpq). While
    /// the database is away, sheets wait in memory (archive_buffer_mb) and
    /// are stored when it is back. Options: archive_*.
    /// </summary>
    public sealed class Archive : IDisposable
    {
        private readonly ArchiveHandle handle;

        static Archive() => NativeLoader.EnsureLoaded();

        public Archive(string location, string line = "", FlatlineOptions? options = null)
        {
            if (location == null)
                throw new ArgumentNullException(nameof(location));
            if (line == null)
                throw new ArgumentNullException(nameof(line));
            using (var scope = FlatlineOptions.Borrow(options))
                FlatlineNative.flt_archive_open(location, line, scope.Handle, out handle);
            handle.Track(0);
        }

        internal ArchiveHandle LiveHandle
        {
            get
            {
                if (handle.IsDisposed)
                    throw new ObjectDisposedException(nameof(Archive));
                return handle;
            }
        }

        /// <summary>"sqlite" or "postgresql".</summary>
        public string Backend
        {
            get
            {
                FlatlineNative.flt_archive_backend(LiveHandle, out int b);
                return b == 1 ? "postgresql" : "sqlite";
            }
        }

        /// <summary>Waits until every sheet given so far is stored; a
        /// <see cref="DeviceTimeoutException"/> with the database's last error
        /// otherwise.</summary>
        public void Flush(int timeoutMs = 30000) =>
            FlatlineNative.flt_archive_flush(LiveHandle, (uint)Math.Max(0, timeoutMs));

        /// <summary>Applies the retention limits now; the sheets removed.</summary>
        public unsafe ulong Prune()
        {
            ulong removed;
            FlatlineNative.flt_archive_prune(LiveHandle, &removed);
            return removed;
        }

        /// <summary>Sheets given, stored, pending and lost, failed attempts,
        /// reconnects, pruned, bytes stored and pending.</summary>
        public unsafe IReadOnlyDictionary<string, ulong> Counters()
        {
            var names = new[] { "sheets", "stored", "pending", "lost", "failures", "reconnects",
                                "pruned", "bytes", "pending_bytes" };
            var live = LiveHandle;
            var result = new Dictionary<string, ulong>();
            for (int i = 0; i < names.Length; ++i)
            {
                ulong v;
                FlatlineNative.flt_archive_count(live, i, &v);
                result[names[i]] = v;
            }
            return result;
        }

        /// <summary>Stores what is pending (archive_close_timeout) and closes.</summary>
        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }
    }
}
