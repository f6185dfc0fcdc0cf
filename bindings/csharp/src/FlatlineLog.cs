// SPDX-License-Identifier: Apache-2.0
using System;
using System.Runtime.InteropServices;

namespace Flatline
{
    /// <summary>How much a log message matters (flt_log_level).</summary>
    public enum FlatlineLogLevel
    {
        /// <summary>Detail for whoever debugs the line.</summary>
        Debug = NativeLogLevel.FLT_LOG_DEBUG,
        /// <summary>The line's course: a strip's head and end, bands found.</summary>
        Information = NativeLogLevel.FLT_LOG_INFO,
        /// <summary>Something was lost or not judged: a result is affected.</summary>
        Warning = NativeLogLevel.FLT_LOG_WARNING,
        /// <summary>Something stopped: a gauge failed, a camera was unplugged.</summary>
        Error = NativeLogLevel.FLT_LOG_ERROR,
    }

    /// <summary>One message of the library's log.</summary>
    public sealed class FlatlineLogEventArgs : EventArgs
    {
        internal FlatlineLogEventArgs(FlatlineLogLevel level, string component, string message)
        {
            Level = level;
            Component = component;
            Message = message;
        }

        /// <summary>How much it matters.</summary>
        public FlatlineLogLevel Level { get; }
        /// <summary>What speaks: "gauge", "camera".</summary>
        public string Component { get; }
        /// <summary>The text, e.g. "sheet 3 (coil 1) is incomplete: coverage 15.3 % ...".</summary>
        public string Message { get; }

        public override string ToString() => $"{Level} {Component}: {Message}";
    }

    /// <summary>
    /// The library's log (flatline/log.h): frames dropped, rows lost,
    /// incomplete sheets, cuts ignored, saturated laser peaks, a strip's head
    /// and end, camera faults and recoveries, as they happen. Add a handler to
    /// <see cref="Message"/>; with none the library says nothing. Each place
    /// in the library passes at most 5 messages in 10 s. Handlers run on the
    /// library's threads (a gauge worker, an acquisition thread), one message
    /// at a time: record the message and return (a handler that calls the
    /// object that speaks may wait for ever). An exception a handler throws
    /// is dropped. To an <c>ILogger</c>:
    /// <code>
    /// FlatlineLog.Message += (sender, e) => logger.Log(
    ///     e.Level switch { FlatlineLogLevel.Error => LogLevel.Error, FlatlineLogLevel.Warning => LogLevel.Warning,
    ///                      FlatlineLogLevel.Information => LogLevel.Information, _ => LogLevel.Debug },
    ///     "{Component}: {Message}", e.Component, e.Message);
    /// </code>
    /// </summary>
    public static class FlatlineLog
    {
        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        private delegate void NativeLogCallback(int level, IntPtr component, IntPtr message, IntPtr user);

        private static readonly object Sync = new object();
        private static readonly NativeLogCallback Callback = OnMessage;  // kept alive for the process
        private static readonly IntPtr CallbackPointer = Marshal.GetFunctionPointerForDelegate(Callback);
        private static EventHandler<FlatlineLogEventArgs>? message;
        private static FlatlineLogLevel minimum = FlatlineLogLevel.Information;

        static FlatlineLog() => NativeLoader.EnsureLoaded();

        /// <summary>The least level passed to <see cref="Message"/> (Information by default).</summary>
        public static FlatlineLogLevel MinimumLevel
        {
            get => minimum;
            set
            {
                lock (Sync)
                {
                    minimum = value;
                    Update();
                }
            }
        }

        /// <summary>Every message at or above <see cref="MinimumLevel"/>.</summary>
        public static event EventHandler<FlatlineLogEventArgs> Message
        {
            add
            {
                lock (Sync)
                {
                    message += value;
                    Update();
                }
            }
            remove
            {
                lock (Sync)
                {
                    message -= value;
                    Update();
                }
            }
        }

        // (Under Sync.) The native callback is set while a handler listens;
        // removing it waits for a message in progress.
        private static void Update()
        {
            FlatlineNative.flt_log_set_callback(message != null ? CallbackPointer : IntPtr.Zero, IntPtr.Zero, (int)minimum);
        }

        private static void OnMessage(int level, IntPtr component, IntPtr text, IntPtr user)
        {
            try
            {
                EventHandler<FlatlineLogEventArgs>? handlers = message;
                handlers?.Invoke(null, new FlatlineLogEventArgs((FlatlineLogLevel)level, Utf8.Decode(component),
                                                                Utf8.Decode(text)));
            }
            catch (Exception)
            {
                // nothing may escape into native code
            }
        }
    }
}
