// SPDX-License-Identifier: Apache-2.0
using System;

namespace Flatline.Testing
{
    // The testing tier (include/flatline/testing.h, libflatline_testing):
    // simulated USB3 Vision cameras with fault injection. Not under
    // libflatline's ABI promise; its native libraries (flatline_testing_csharp
    // and libflatline_testing) load at the first call into this namespace.

    /// <summary>Settings and read-outs of a simulated camera (flt_u3v_sim_param).</summary>
    public enum U3VSimParam
    {
        ResponseTimeMs = NativeSimParam.FLT_U3V_SIM_RESPONSE_TIME_MS,
        MaxCommandBytes = NativeSimParam.FLT_U3V_SIM_MAX_COMMAND_BYTES,
        MaxAckBytes = NativeSimParam.FLT_U3V_SIM_MAX_ACK_BYTES,
        AlignmentLog2 = NativeSimParam.FLT_U3V_SIM_ALIGNMENT_LOG2,
        XmlZipped = NativeSimParam.FLT_U3V_SIM_XML_ZIPPED,
        /// <summary>1: append the encoder count as a chunk.</summary>
        EncoderChunk = NativeSimParam.FLT_U3V_SIM_ENCODER_CHUNK,
        EncoderChunkId = NativeSimParam.FLT_U3V_SIM_ENCODER_CHUNK_ID,
        /// <summary>Micrometres of travel per encoder count.</summary>
        EncoderMmPerCountUm = NativeSimParam.FLT_U3V_SIM_ENCODER_MM_PER_COUNT_UM,
        SpeedMbps = NativeSimParam.FLT_U3V_SIM_SPEED_MBPS,
        /// <summary>1: the camera was left streaming by a process that died.</summary>
        LeftStreaming = NativeSimParam.FLT_U3V_SIM_LEFT_STREAMING,
        // read-only
        SiControl = NativeSimParam.FLT_U3V_SIM_SI_CONTROL,
        Acquiring = NativeSimParam.FLT_U3V_SIM_ACQUIRING,
        Commands = NativeSimParam.FLT_U3V_SIM_COMMANDS,
        LastReadTimeoutMs = NativeSimParam.FLT_U3V_SIM_LAST_READ_TIMEOUT_MS,
        FramesSent = NativeSimParam.FLT_U3V_SIM_FRAMES_SENT,
        Open = NativeSimParam.FLT_U3V_SIM_OPEN,
        /// <summary>Control-channel and submit faults not yet applied in full.</summary>
        FaultsPending = NativeSimParam.FLT_U3V_SIM_FAULTS_PENDING,
        /// <summary>1 once the camera was unplugged.</summary>
        Unplugged = NativeSimParam.FLT_U3V_SIM_UNPLUGGED,
    }

    /// <summary>Faults a simulated camera can inject (flt_u3v_fault); see
    /// include/flatline/testing.h for what each does.</summary>
    public enum U3VFault
    {
        ShortFrame = NativeSimFault.FLT_U3V_FAULT_SHORT_FRAME,
        LeaderMidFrame = NativeSimFault.FLT_U3V_FAULT_LEADER_MID_FRAME,
        Overflow = NativeSimFault.FLT_U3V_FAULT_OVERFLOW,
        SkipBlockIds = NativeSimFault.FLT_U3V_FAULT_SKIP_BLOCK_IDS,
        StreamTimeout = NativeSimFault.FLT_U3V_FAULT_STREAM_TIMEOUT,
        Unplug = NativeSimFault.FLT_U3V_FAULT_UNPLUG,
        Garbage = NativeSimFault.FLT_U3V_FAULT_GARBAGE,
        TrailerStatus = NativeSimFault.FLT_U3V_FAULT_TRAILER_STATUS,
        SubmitRefused = NativeSimFault.FLT_U3V_FAULT_SUBMIT_REFUSED,
        PendingAck = NativeSimFault.FLT_U3V_FAULT_PENDING_ACK,
        ControlTimeout = NativeSimFault.FLT_U3V_FAULT_CONTROL_TIMEOUT,
        LateAck = NativeSimFault.FLT_U3V_FAULT_LATE_ACK,
        /// <summary>Commands executed, their acknowledges lost.</summary>
        LostAck = NativeSimFault.FLT_U3V_FAULT_LOST_ACK,
        /// <summary>Commands answered "busy", not executed.</summary>
        Busy = NativeSimFault.FLT_U3V_FAULT_BUSY,
        /// <summary>Unplugged when a command arrives.</summary>
        ControlUnplug = NativeSimFault.FLT_U3V_FAULT_CONTROL_UNPLUG,
    }

    /// <summary>
    /// A simulated USB bus with simulated USB3 Vision cameras (flt_u3v_sim):
    /// the real client code of <see cref="FrameSource.U3V"/> talks to it
    /// through the same transport interface as libusb, so tests and
    /// integrators run the whole camera path without hardware. Cameras answer
    /// GenCP, describe themselves in a GenICam XML and stream leader, payload
    /// and trailer transfers: a test pattern, or the frames of a
    /// <see cref="SimulatedLine"/> (<see cref="SetFrames"/>), optionally with
    /// an encoder chunk and injected faults. Time is virtual: a simulated
    /// timeout returns at once.
    /// </summary>
    /// <remarks>
    /// Sources opened on the bus hold it, and the bus holds the lines it
    /// renders, so any dispose order is safe. Not thread-safe, nor to be used
    /// while a source on it runs on another thread.
    /// </remarks>
    public sealed class U3VSimBus : IDisposable
    {
        private readonly U3VSimHandle handle;

        static U3VSimBus() => NativeLoader.EnsureTestingLoaded();

        /// <summary>An empty bus (plus one device that is not a camera).</summary>
        public U3VSimBus()
        {
            FlatlineTestingNative.flt_u3v_sim_create(out handle);
            handle.Track(0);
        }

        /// <summary>Adds a camera (at most 8) and returns its index: strings of
        /// at most 63 bytes, a <paramref name="width"/> x <paramref name="height"/>
        /// sensor (16..8192 px each).</summary>
        public unsafe int AddCamera(string vendor, string model, string serial, int width, int height,
                                    PixelFormat format = PixelFormat.Mono8)
        {
            var live = LiveHandle;
            if (vendor == null)
                throw new ArgumentNullException(nameof(vendor));
            if (model == null)
                throw new ArgumentNullException(nameof(model));
            if (serial == null)
                throw new ArgumentNullException(nameof(serial));
            Shapes.AtLeast(width, 0, nameof(width));
            Shapes.AtLeast(height, 0, nameof(height));
            ulong index;
            FlatlineTestingNative.flt_u3v_sim_add_camera(live, vendor, model, serial, (uint)width, (uint)height, (int)format,
                                                  &index);
            return (int)index;
        }

        /// <summary>Renders camera <paramref name="camera"/>'s frames with
        /// <paramref name="line"/> (held by the bus), or the test pattern for
        /// null. The camera takes the line's frame size and format.</summary>
        public void SetFrames(int camera, SimulatedLine? line)
        {
            var live = LiveHandle;
            var sim = line != null ? line.LiveHandle : new SimHandle();
            FlatlineTestingNative.flt_u3v_sim_set_frames(live, Camera(camera), sim);
            live.Hold(sim);
        }

        /// <summary>Sets a parameter of a camera (before it is opened).</summary>
        public void Set(int camera, U3VSimParam param, ulong value) =>
            FlatlineTestingNative.flt_u3v_sim_set(LiveHandle, Camera(camera), (int)param, value);

        /// <summary>Reads a parameter or read-out of a camera.</summary>
        public unsafe ulong Get(int camera, U3VSimParam param)
        {
            ulong value;
            FlatlineTestingNative.flt_u3v_sim_get(LiveHandle, Camera(camera), (int)param, &value);
            return value;
        }

        /// <summary>Schedules a fault: stream faults on the frame with block id
        /// <paramref name="at"/>; host faults on <paramref name="count"/>
        /// operations (commands, bulk submissions) after the next
        /// <paramref name="at"/> ones. Faults add up.</summary>
        public void Inject(int camera, U3VFault fault, ulong at = 0, uint count = 1) =>
            FlatlineTestingNative.flt_u3v_sim_inject(LiveHandle, Camera(camera), (int)fault, at, count);

        /// <summary>A 32-bit register of the camera's map, read directly (no GenCP).</summary>
        public unsafe uint Peek(int camera, ulong address)
        {
            uint value;
            FlatlineTestingNative.flt_u3v_sim_peek(LiveHandle, Camera(camera), address, &value);
            return value;
        }

        /// <summary>Frees the bus now, or as soon as the last source opened on
        /// it is disposed. Further calls throw <see cref="ObjectDisposedException"/>;
        /// a second Dispose does nothing.</summary>
        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }

        /// <summary>The bus as the flt_usb_transport FrameSource.U3V and
        /// FrameSource.Cameras pass to libflatline (owned by the bus: valid
        /// while its handle lives).</summary>
        internal IntPtr Transport
        {
            get
            {
                FlatlineTestingNative.flt_u3v_sim_transport(LiveHandle, out IntPtr transport);
                return transport;
            }
        }

        internal U3VSimHandle LiveHandle
        {
            get
            {
                if (handle.IsDisposed)
                    throw new ObjectDisposedException(nameof(U3VSimBus));
                return handle;
            }
        }

        private static ulong Camera(int camera)
        {
            if (camera < 0)
                throw new ArgumentOutOfRangeException(nameof(camera), camera, "camera must be >= 0");
            return (ulong)camera;
        }
    }
}
