// SPDX-License-Identifier: Apache-2.0
using System;
using System.Runtime.InteropServices;
using System.Threading;

namespace Flatline
{
    /// <summary>
    /// The owner of one native handle. The P/Invoke marshaller creates it
    /// (out parameters of flt_x_create), keeps it alive during every call it
    /// is passed to, and refuses it once closed; its finalizer is the safety
    /// net that frees a handle nobody disposed. Subclasses name the destroy
    /// function. Live handles are counted per type so that tests can check
    /// that finalization really frees them.
    /// </summary>
    internal abstract class FlatlineHandle : SafeHandle
    {
        private long pressure;
        private bool tracked;
        private SafeHandle[] held = Array.Empty<SafeHandle>();

        protected FlatlineHandle() : base(IntPtr.Zero, ownsHandle: true) { }

        public override bool IsInvalid => handle == IntPtr.Zero;

        private volatile bool disposed;

        /// <summary>Disposed by its owner. A handle another handle holds
        /// (see <see cref="Hold"/>) stays open until released, but its owner
        /// must refuse further calls from the moment it is disposed.</summary>
        internal bool IsDisposed => disposed || IsClosed;

        protected override void Dispose(bool disposing)
        {
            disposed = true;
            base.Dispose(disposing);
        }

        /// <summary>Called once the native create succeeded: counts the handle
        /// and tells the GC about the native memory it holds, so that objects
        /// nobody disposes are collected before native memory runs out.</summary>
        internal void Track(long nativeBytes)
        {
            pressure = Math.Max(0, nativeBytes);
            if (pressure > 0)
                GC.AddMemoryPressure(pressure);
            tracked = true;
            OnLive(+1);
        }

        /// <summary>Keeps <paramref name="parent"/>'s native object alive
        /// for as long as this handle's: the C object borrows it (a frame
        /// source its simulator or simulated bus, a simulated camera its
        /// simulator). The parent's reference count is raised now and
        /// lowered after this handle's destroy, so disposing or finalizing
        /// the parent first only defers its destroy, in either order.</summary>
        internal void Hold(SafeHandle parent)
        {
            if (parent == null || parent.IsInvalid)
                return;
            bool added = false;
            parent.DangerousAddRef(ref added);
            lock (this)
            {
                var grown = new SafeHandle[held.Length + 1];
                held.CopyTo(grown, 0);
                grown[held.Length] = parent;
                held = grown;
            }
        }

        protected abstract void Destroy(IntPtr native);
        protected abstract void OnLive(int delta);

        protected override bool ReleaseHandle()
        {
            Destroy(handle);
            foreach (var parent in held)
                parent.DangerousRelease();
            held = Array.Empty<SafeHandle>();
            if (pressure > 0)
                GC.RemoveMemoryPressure(pressure);
            if (tracked)
                OnLive(-1);
            return true;
        }
    }

    internal sealed class OptionsHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public OptionsHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_options_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class ReconHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public ReconHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_recon_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class CalibHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public CalibHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_calib_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class SimHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public SimHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_sim_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class ExtractorHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public ExtractorHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_extractor_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class FlatnessHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public FlatnessHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_flatness_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class SourceHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public SourceHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_source_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class CameraListHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public CameraListHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_camera_list_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class U3VSimHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public U3VSimHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineTestingNative.flt_u3v_sim_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class GaugeHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public GaugeHandle() { }
        // Removes the callback before destroying: no sheet may reach a
        // delegate while the gauge shuts down (see swig/gauge.i).
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_cs_gauge_release(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class SheetHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public SheetHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_sheet_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class GenICamHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public GenICamHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_genicam_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class RulesHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public RulesHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_rules_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class VerdictHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public VerdictHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_verdict_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class AdvisorHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public AdvisorHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_advisor_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class CoilInfoHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public CoilInfoHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_coil_info_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class RecorderHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public RecorderHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_recorder_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class RecordingHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public RecordingHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_recording_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }

    internal sealed class ArchiveHandle : FlatlineHandle
    {
        private static long live;
        internal static long Live => Interlocked.Read(ref live);
        public ArchiveHandle() { }
        protected override void Destroy(IntPtr native) => FlatlineNative.flt_archive_destroy_handle(native);
        protected override void OnLive(int delta) => Interlocked.Add(ref live, delta);
    }
}
