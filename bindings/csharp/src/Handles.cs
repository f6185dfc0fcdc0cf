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

        protected FlatlineHandle() : base(IntPtr.Zero, ownsHandle: true) { }

        public override bool IsInvalid => handle == IntPtr.Zero;

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

        protected abstract void Destroy(IntPtr native);
        protected abstract void OnLive(int delta);

        protected override bool ReleaseHandle()
        {
            Destroy(handle);
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
}
