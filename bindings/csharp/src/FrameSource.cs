// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.Runtime.InteropServices;
using Flatline.Testing;

namespace Flatline
{
    /// <summary>What a <see cref="FrameSource"/> reads (flt_source_kind).</summary>
    public enum SourceKind
    {
        Simulator = NativeSourceKind.FLT_SOURCE_SIMULATOR,
        Images = NativeSourceKind.FLT_SOURCE_IMAGES,
        U3V = NativeSourceKind.FLT_SOURCE_U3V,
        GigE = NativeSourceKind.FLT_SOURCE_GIGE,
        /// <summary>A recording (<see cref="FrameSource.OpenRecording"/>).</summary>
        Recording = NativeSourceKind.FLT_SOURCE_RECORDING,
    }

    /// <summary>Where a frame's encoder position comes from (the option
    /// source_encoder_mode, flt_encoder_mode; see include/flatline/source.h).</summary>
    public enum EncoderMode
    {
        /// <summary>Simulator: its own; images: the CSV when given, else fixed step; camera: fixed step.</summary>
        Auto = NativeEncoderMode.FLT_ENCODER_AUTO,
        /// <summary>SourceEncoderStart + SourceEncoderStep * (block id - first block id).</summary>
        FixedStep = NativeEncoderMode.FLT_ENCODER_FIXED_STEP,
        /// <summary>The value last given to <see cref="FrameSource.SetEncoder"/>.</summary>
        Host = NativeEncoderMode.FLT_ENCODER_HOST,
        /// <summary>A USB3 Vision camera's encoder counter chunk.</summary>
        Chunk = NativeEncoderMode.FLT_ENCODER_CHUNK,
    }

    /// <summary>Frame and channel counters of a source (flt_source_counter).</summary>
    public enum SourceCounter
    {
        Frames = NativeCounter.FLT_COUNT_FRAMES,
        Dropped = NativeCounter.FLT_COUNT_DROPPED,
        Short = NativeCounter.FLT_COUNT_SHORT,
        Incomplete = NativeCounter.FLT_COUNT_INCOMPLETE,
        Overflow = NativeCounter.FLT_COUNT_OVERFLOW,
        SubmitDropped = NativeCounter.FLT_COUNT_SUBMIT_DROPPED,
        TimeoutDropped = NativeCounter.FLT_COUNT_TIMEOUT_DROPPED,
        Lost = NativeCounter.FLT_COUNT_LOST,
        SubmitRefused = NativeCounter.FLT_COUNT_SUBMIT_REFUSED,
        Timeouts = NativeCounter.FLT_COUNT_TIMEOUTS,
        Disconnects = NativeCounter.FLT_COUNT_DISCONNECTS,
        BadPackets = NativeCounter.FLT_COUNT_BAD_PACKETS,
        BadLeaders = NativeCounter.FLT_COUNT_BAD_LEADERS,
        PendingAcks = NativeCounter.FLT_COUNT_PENDING_ACKS,
        StaleAcks = NativeCounter.FLT_COUNT_STALE_ACKS,
        CommandRetries = NativeCounter.FLT_COUNT_COMMAND_RETRIES,
        StreamRecoveries = NativeCounter.FLT_COUNT_STREAM_RECOVERIES,
        /// <summary>GigE Vision: packets found missing (each once).</summary>
        PacketsMissing = NativeCounter.FLT_COUNT_PACKETS_MISSING,
        /// <summary>GigE Vision: packets asked again (each request).</summary>
        ResendRequests = NativeCounter.FLT_COUNT_RESEND_REQUESTS,
        /// <summary>GigE Vision: missing packets that came after a request.</summary>
        PacketsResent = NativeCounter.FLT_COUNT_PACKETS_RESENT,
        /// <summary>GigE Vision: packets that came twice or too late.</summary>
        PacketsDuplicate = NativeCounter.FLT_COUNT_PACKETS_DUPLICATE,
    }

    /// <summary>Camera strings from the bootstrap registers (flt_camera_string).</summary>
    public enum CameraString
    {
        Vendor = NativeCameraString.FLT_CAMERA_VENDOR,
        Model = NativeCameraString.FLT_CAMERA_MODEL,
        Family = NativeCameraString.FLT_CAMERA_FAMILY,
        DeviceVersion = NativeCameraString.FLT_CAMERA_DEVICE_VERSION,
        ManufacturerInfo = NativeCameraString.FLT_CAMERA_MANUFACTURER_INFO,
        Serial = NativeCameraString.FLT_CAMERA_SERIAL,
        UserName = NativeCameraString.FLT_CAMERA_USER_NAME,
    }

    /// <summary>Camera values read from the registers or chosen for the
    /// stream (flt_camera_value; see include/flatline/source.h).</summary>
    public enum CameraValue
    {
        GenCPVersion = NativeCameraValue.FLT_CAMERA_GENCP_VERSION,
        U3VVersion = NativeCameraValue.FLT_CAMERA_U3V_VERSION,
        ResponseTimeMs = NativeCameraValue.FLT_CAMERA_RESPONSE_TIME_MS,
        ControlTimeoutMs = NativeCameraValue.FLT_CAMERA_CONTROL_TIMEOUT_MS,
        MaxCommandBytes = NativeCameraValue.FLT_CAMERA_MAX_COMMAND_BYTES,
        MaxAckBytes = NativeCameraValue.FLT_CAMERA_MAX_ACK_BYTES,
        SirmAddress = NativeCameraValue.FLT_CAMERA_SIRM_ADDRESS,
        ManifestAddress = NativeCameraValue.FLT_CAMERA_MANIFEST_ADDRESS,
        XmlBytes = NativeCameraValue.FLT_CAMERA_XML_BYTES,
        XmlZipped = NativeCameraValue.FLT_CAMERA_XML_ZIPPED,
        SpeedMbps = NativeCameraValue.FLT_CAMERA_SPEED_MBPS,
        Alignment = NativeCameraValue.FLT_CAMERA_ALIGNMENT,
        PayloadBytes = NativeCameraValue.FLT_CAMERA_PAYLOAD_BYTES,
        TransferBytes = NativeCameraValue.FLT_CAMERA_TRANSFER_BYTES,
        TransferCount = NativeCameraValue.FLT_CAMERA_TRANSFER_COUNT,
        FinalTransferBytes = NativeCameraValue.FLT_CAMERA_FINAL_TRANSFER_BYTES,
        MaxLeaderBytes = NativeCameraValue.FLT_CAMERA_MAX_LEADER_BYTES,
        MaxTrailerBytes = NativeCameraValue.FLT_CAMERA_MAX_TRAILER_BYTES,
        GevVersion = NativeCameraValue.FLT_CAMERA_GEV_VERSION,
        /// <summary>IPv4 address, a &lt;&lt; 24 | b &lt;&lt; 16 | c &lt;&lt; 8 | d.</summary>
        IpAddress = NativeCameraValue.FLT_CAMERA_IP_ADDRESS,
        HeartbeatTimeoutMs = NativeCameraValue.FLT_CAMERA_HEARTBEAT_TIMEOUT_MS,
        Heartbeats = NativeCameraValue.FLT_CAMERA_HEARTBEATS,
        /// <summary>Negotiated stream packet size, bytes (IP + UDP + GVSP headers + data).</summary>
        PacketSize = NativeCameraValue.FLT_CAMERA_PACKET_SIZE,
        StreamPort = NativeCameraValue.FLT_CAMERA_STREAM_PORT,
        TimestampHz = NativeCameraValue.FLT_CAMERA_TIMESTAMP_HZ,
        ResendCapable = NativeCameraValue.FLT_CAMERA_RESEND_CAPABLE,
        ReceiveBufferBytes = NativeCameraValue.FLT_CAMERA_RECEIVE_BUFFER_BYTES,
    }

    /// <summary>A camera found by <see cref="FrameSource.Cameras"/> (USB3
    /// Vision) or <see cref="FrameSource.GigECameras"/> (GigE Vision): its
    /// strings, link speed (Mbit/s; 0 unknown) and address. A USB3 Vision
    /// camera that cannot be opened to read its strings is listed with
    /// vendor "?" and the reason as its model.</summary>
    public sealed class CameraInfo
    {
        internal CameraInfo(string vendor, string model, string serial, int speedMbps,
                            string address = "")
        {
            Vendor = vendor;
            Model = model;
            Serial = serial;
            SpeedMbps = speedMbps;
            Address = address;
        }

        public string Vendor { get; }
        public string Model { get; }
        public string Serial { get; }
        public int SpeedMbps { get; }
        /// <summary>GigE Vision: "a.b.c.d" (":port" when not 3956), what
        /// <see cref="FrameSource.GigE"/> opens; USB3 Vision: "".</summary>
        public string Address { get; }
        public override string ToString() => $"{Vendor} {Model} ({Serial}), {SpeedMbps} Mbit/s";
    }

    /// <summary>
    /// A frame from <see cref="FrameSource.Next"/>, copied out of the
    /// source's buffer (the C frame lives only until the next call), so it
    /// stays valid. Exactly one of <see cref="Pixels8"/> (Mono8) and
    /// <see cref="Pixels16"/> (Mono10/12/16, data in the low bits) is set,
    /// [height, width] (rows, columns) without the source's row padding.
    /// </summary>
    public sealed class Frame
    {
        internal Frame(PixelFormat format, int width, int height)
        {
            Format = format;
            Pixels = format == PixelFormat.Mono8 ? new byte[height, width] : (Array)new ushort[height, width];
        }

        public PixelFormat Format { get; }
        /// <summary>Mono8: the pixels [height, width]; null for a 16-bit format.</summary>
        public byte[,]? Pixels8 => Pixels as byte[,];
        /// <summary>Mono10/12/16: the pixels [height, width]; null for Mono8.</summary>
        public ushort[,]? Pixels16 => Pixels as ushort[,];
        /// <summary>The pixels whatever the format: a byte[,] or a ushort[,].</summary>
        public Array Pixels { get; }
        public int Width => Pixels.GetLength(1);
        public int Height => Pixels.GetLength(0);
        /// <summary>The row pitch of the source's buffer, bytes (&gt;= width *
        /// bytes per pixel; the managed copy is packed).</summary>
        public long StrideBytes { get; internal set; }
        /// <summary>The camera's frame counter (simulator and images: the frame index).</summary>
        public ulong BlockId { get; internal set; }
        /// <summary>Camera: the leader's timestamp (device clock, ns);
        /// otherwise the host's monotonic clock at delivery, ns.</summary>
        public ulong TimestampNs { get; internal set; }
        /// <summary>The strip position, mm (see <see cref="EncoderMode"/>).</summary>
        public double EncoderMm { get; internal set; }

        internal bool Fits(PixelFormat format, int width, int height) =>
            Format == format && Width == width && Height == height;
    }

    /// <summary>
    /// A source of camera frames (flt_source): a USB3 Vision camera (over
    /// libusb, no camera SDK; or a simulated camera of a
    /// <see cref="Flatline.Testing.U3VSimBus"/>),
    /// recorded image files, or a <see cref="SimulatedLine"/>, behind one
    /// loop: <see cref="Start"/>, then <see cref="Next"/> until it returns
    /// null (end of images) or throws. Every frame carries its encoder
    /// position. See include/flatline/source.h for the encoder modes, the
    /// frame accounting and the GenICam features.
    /// </summary>
    /// <remarks>
    /// A source keeps what it borrows alive: the <see cref="SimulatedLine"/>
    /// of <see cref="Simulator"/> and the <see cref="U3VSimBus"/> of
    /// <see cref="U3V"/> (disposing them first only defers their native
    /// destroy until the source is gone). Not thread-safe: one thread at a
    /// time, and a simulated bus not from another thread while a source on
    /// it is used. Errors: <see cref="DeviceTimeoutException"/> when no good
    /// frame came in time, <see cref="DeviceException"/> when the camera is
    /// gone (then on every later call; Dispose still works),
    /// <see cref="NotFoundException"/> for an unknown serial or feature.
    /// </remarks>
    public sealed class FrameSource : IDisposable
    {
        private readonly SourceHandle handle;

        static FrameSource() => NativeLoader.EnsureLoaded();

        private FrameSource(SourceHandle handle, object? parent, long nativeBytes = 0)
        {
            this.handle = handle;
            Parent = parent;
            unsafe
            {
                int kind;
                FlatlineNative.flt_source_kind_of(handle, &kind);
                Kind = (SourceKind)kind;
            }
            handle.Track(nativeBytes);
        }

        /// <summary>Frames rendered by <paramref name="line"/> (which may still
        /// change its sheet between frames), each with the line's encoder
        /// position (or fixed step / host mode; Chunk is refused).</summary>
        public static FrameSource Simulator(SimulatedLine line, FlatlineOptions? options = null)
        {
            if (line == null)
                throw new ArgumentNullException(nameof(line));
            NativeLoader.EnsureLoaded();
            SourceHandle handle;
            var sim = line.LiveHandle;
            using (var scope = FlatlineOptions.Borrow(options))
            {
                FlatlineNative.flt_source_create_sim(sim, scope.Handle, out handle);
            }
            handle.Hold(sim);
            // Its one frame buffer (source.h), as memory pressure.
            long frameBytes = (long)line.FrameWidth * line.FrameHeight * (line.PixelFormat == PixelFormat.Mono8 ? 1 : 2);
            return new FrameSource(handle, line, frameBytes);
        }

        /// <summary>Image files (PNG, TIFF, ...; single channel, 8 or 16 bits,
        /// all of the first one's size) in the given order.
        /// <paramref name="encoderCsv"/>: null (fixed step), or a CSV of the
        /// positions, mm, one row per image ("encoder_mm" or
        /// "file name,encoder_mm"). <see cref="FlatlineFormatException"/>
        /// names a bad CSV line; <see cref="FlatlineIOException"/> an
        /// unreadable image.</summary>
        public static unsafe FrameSource Images(IReadOnlyList<string> paths, string? encoderCsv = null,
                                                FlatlineOptions? options = null)
        {
            if (paths == null)
                throw new ArgumentNullException(nameof(paths));
            if (paths.Count == 0)
                throw new ArgumentException("paths is empty: at least one image", nameof(paths));
            NativeLoader.EnsureLoaded();
            var pins = new GCHandle[paths.Count];
            var pointers = new IntPtr[paths.Count];
            SourceHandle handle;
            try
            {
                for (int i = 0; i < paths.Count; ++i)
                {
                    if (paths[i] == null)
                        throw new ArgumentNullException($"{nameof(paths)}[{i}]");
                    pins[i] = GCHandle.Alloc(Utf8.Encode(paths[i]), GCHandleType.Pinned);
                    pointers[i] = pins[i].AddrOfPinnedObject();
                }
                using (var scope = FlatlineOptions.Borrow(options))
                fixed (IntPtr* pp = pointers)
                {
                    FlatlineNative.flt_source_create_images(pp, (ulong)paths.Count, encoderCsv, scope.Handle,
                                                            out handle);
                }
            }
            finally
            {
                foreach (var pin in pins)
                    if (pin.IsAllocated)
                        pin.Free();
            }
            return new FrameSource(handle, null);
        }

        /// <summary>A recording (<see cref="Recorder"/>) replayed: one frame per
        /// recorded row, in order, with its recorded encoder position. Give it
        /// to <see cref="Gauge.RunAsync"/>: a gauge made with the recording's
        /// own calibration and options gives the live sheets bit for bit.</summary>
        public static FrameSource OpenRecording(string path, FlatlineOptions? options = null)
        {
            if (path == null)
                throw new ArgumentNullException(nameof(path));
            NativeLoader.EnsureLoaded();
            SourceHandle handle;
            using (var scope = FlatlineOptions.Borrow(options))
            {
                FlatlineNative.flt_source_open_recording(path, scope.Handle, out handle);
            }
            return new FrameSource(handle, null);
        }

        /// <summary>Every *.png, *.tif and *.tiff file of
        /// <paramref name="directory"/> (not its sub-folders), sorted by name.
        /// <see cref="NotFoundException"/> if there is none.</summary>
        public static FrameSource ImageDirectory(string directory, string? encoderCsv = null,
                                                 FlatlineOptions? options = null)
        {
            if (directory == null)
                throw new ArgumentNullException(nameof(directory));
            NativeLoader.EnsureLoaded();
            SourceHandle handle;
            using (var scope = FlatlineOptions.Borrow(options))
            {
                FlatlineNative.flt_source_create_image_dir(directory, encoderCsv, scope.Handle, out handle);
            }
            return new FrameSource(handle, null);
        }

        /// <summary>Opens a USB3 Vision camera: the one with
        /// <paramref name="serial"/>, or the first when null; on the USB bus,
        /// or on <paramref name="bus"/> when given (which the source holds).
        /// <see cref="NotFoundException"/> names a serial that is not present;
        /// <see cref="DeviceException"/> says why a camera cannot be opened.</summary>
        public static FrameSource U3V(string? serial = null, FlatlineOptions? options = null, U3VSimBus? bus = null)
        {
            NativeLoader.EnsureLoaded();
            SourceHandle handle;
            using (var scope = FlatlineOptions.Borrow(options))
            {
                // IntPtr.Zero: the real USB bus (libusb); the testing tier is
                // touched (and its library loaded) only when a bus is given.
                IntPtr usb = bus != null ? bus.Transport : IntPtr.Zero;
                FlatlineNative.flt_source_open_u3v(usb, serial, scope.Handle, out handle);
            }
            if (bus != null)
                handle.Hold(bus.LiveHandle);
            GC.KeepAlive(bus);
            return new FrameSource(handle, bus);
        }

        /// <summary>The USB3 Vision cameras present on the USB bus, or on
        /// <paramref name="bus"/>. <see cref="DeviceException"/> if libusb
        /// cannot start.</summary>
        public static unsafe IReadOnlyList<CameraInfo> Cameras(U3VSimBus? bus = null)
        {
            NativeLoader.EnsureLoaded();
            var cameras = new List<CameraInfo>();
            IntPtr usb = bus != null ? bus.Transport : IntPtr.Zero;
            FlatlineNative.flt_camera_list_create(usb, out CameraListHandle list);
            using (list)
            {
                FlatlineNative.flt_camera_list_count(list, out UIntPtr count);
                for (ulong i = 0; i < count.ToUInt64(); ++i)
                {
                    IntPtr vendor, model, serial;
                    uint speed;
                    FlatlineNative.flt_camera_list_get(list, i, &vendor, &model, &serial, &speed);
                    cameras.Add(new CameraInfo(Utf8.Decode(vendor), Utf8.Decode(model), Utf8.Decode(serial),
                                               (int)speed));
                }
            }
            GC.KeepAlive(bus);
            return cameras;
        }

        /// <summary>Opens a GigE Vision camera: <paramref name="camera"/> is
        /// its address ("a.b.c.d" or "a.b.c.d:port"), its serial number or
        /// user-defined name (found by a discovery broadcast), or null for the
        /// first camera that answers. Takes the control privilege (kept by a
        /// heartbeat), reads the bootstrap registers and the GenICam file and
        /// negotiates the stream packet size (options GigE*).
        /// <see cref="NotFoundException"/> when no such camera answers,
        /// <see cref="DeviceTimeoutException"/> when the address does not
        /// answer, <see cref="DeviceException"/> when another application
        /// controls the camera.</summary>
        public static FrameSource GigE(string? camera = null, FlatlineOptions? options = null)
        {
            NativeLoader.EnsureLoaded();
            SourceHandle handle;
            using (var scope = FlatlineOptions.Borrow(options))
            {
                FlatlineNative.flt_source_open_gige(camera, scope.Handle, out handle);
            }
            return new FrameSource(handle, null);
        }

        /// <summary>The GigE Vision cameras that answer a discovery sent to
        /// <paramref name="address"/> (a camera or a subnet's broadcast
        /// address, "a.b.c.d[:port]"), or to every interface's broadcast
        /// address when null, within <paramref name="timeoutMs"/>
        /// (1..60000).</summary>
        public static unsafe IReadOnlyList<CameraInfo> GigECameras(string? address = null, int timeoutMs = 1000)
        {
            if (timeoutMs < 1 || timeoutMs > 60000)
                throw new ArgumentOutOfRangeException(nameof(timeoutMs), timeoutMs, "1..60000 ms");
            NativeLoader.EnsureLoaded();
            var cameras = new List<CameraInfo>();
            FlatlineNative.flt_camera_list_create_gige(address, (uint)timeoutMs, out CameraListHandle list);
            using (list)
            {
                FlatlineNative.flt_camera_list_count(list, out UIntPtr count);
                for (ulong i = 0; i < count.ToUInt64(); ++i)
                {
                    IntPtr vendor, model, serial, where;
                    uint speed;
                    FlatlineNative.flt_camera_list_get(list, i, &vendor, &model, &serial, &speed);
                    FlatlineNative.flt_camera_list_address(list, i, &where);
                    cameras.Add(new CameraInfo(Utf8.Decode(vendor), Utf8.Decode(model), Utf8.Decode(serial),
                                               (int)speed, Utf8.Decode(where)));
                }
            }
            return cameras;
        }

        public SourceKind Kind { get; }
        /// <summary>What the source borrows: its SimulatedLine or U3VSimBus, else null.</summary>
        public object? Parent { get; }

        /// <summary>Starts acquisition (a camera: stream set-up, buffers,
        /// AcquisitionStart; images start again from the first).
        /// <see cref="FlatlineStateException"/> if already started.</summary>
        public void Start() => FlatlineNative.flt_source_start(LiveHandle);

        /// <summary>Stops acquisition; stopping a stopped source does nothing.</summary>
        public void Stop() => FlatlineNative.flt_source_stop(LiveHandle);

        /// <summary>Waits up to <paramref name="timeoutMs"/> for the next good
        /// frame and copies it out: into <paramref name="reuse"/> when it has
        /// the frame's format and size (a loop allocates nothing then), else
        /// into a new <see cref="Frame"/>. Null at the end of an image
        /// sequence. <see cref="DeviceTimeoutException"/>,
        /// <see cref="DeviceException"/>, <see cref="FlatlineStateException"/>
        /// before <see cref="Start"/>.</summary>
        public unsafe Frame? Next(int timeoutMs = 1000, Frame? reuse = null)
        {
            var live = LiveHandle;
            if (timeoutMs < 0)
                throw new ArgumentOutOfRangeException(nameof(timeoutMs), timeoutMs, "timeoutMs must be >= 0");
            IntPtr native;
            FlatlineNative.flt_source_next(live, (uint)timeoutMs, &native);
            if (native == IntPtr.Zero)
                return null;
            IntPtr pixels;
            uint width, height;
            ulong stride, blockId, timestamp;
            int format;
            double encoder;
            FlatlineNative.flt_frame_info(native, &pixels, out width, out height, &stride, &format, &blockId, &timestamp,
                                          &encoder);
            var pixelFormat = (PixelFormat)format;
            var frame = reuse != null && reuse.Fits(pixelFormat, (int)width, (int)height)
                ? reuse
                : new Frame(pixelFormat, (int)width, (int)height);
            int rowBytes = (int)width * (pixelFormat == PixelFormat.Mono8 ? 1 : 2);
            byte* source = (byte*)pixels;
            if (frame.Pixels is byte[,] pixels8)
            {
                fixed (byte* target = pixels8)
                    CopyRows(source, (long)stride, target, rowBytes, (int)height);
            }
            else
            {
                fixed (ushort* target = (ushort[,])frame.Pixels)
                    CopyRows(source, (long)stride, (byte*)target, rowBytes, (int)height);
            }
            frame.StrideBytes = (long)stride;
            frame.BlockId = blockId;
            frame.TimestampNs = timestamp;
            frame.EncoderMm = encoder;
            return frame;
        }

        /// <summary>Encoder mode Host: the position (mm, finite) the next
        /// frames carry. <see cref="FlatlineStateException"/> in any other mode.</summary>
        public void SetEncoder(double encoderMm) => FlatlineNative.flt_source_set_encoder(LiveHandle, encoderMm);

        /// <summary>One counter, since the source was created.</summary>
        public unsafe ulong Count(SourceCounter counter)
        {
            ulong value;
            FlatlineNative.flt_source_count(LiveHandle, (int)counter, &value);
            return value;
        }

        /// <summary>Every counter, since the source was created.</summary>
        public IReadOnlyDictionary<SourceCounter, ulong> Counters
        {
            get
            {
                var counters = new Dictionary<SourceCounter, ulong>();
                foreach (SourceCounter counter in Enum.GetValues(typeof(SourceCounter)))
                    counters[counter] = Count(counter);
                return counters;
            }
        }

        /// <summary>Why the last frame was dropped or lost ("" if none was).</summary>
        public string StreamError => FlatlineNative.flt_source_stream_error(LiveHandle);

        /// <summary>A camera string. <see cref="FlatlineStateException"/> for a
        /// source that is not a camera.</summary>
        public unsafe string GetCameraString(CameraString which)
        {
            IntPtr text;
            FlatlineNative.flt_source_camera_string(LiveHandle, (int)which, &text);
            return Utf8.Decode(text);
        }

        /// <summary>A camera value. <see cref="FlatlineStateException"/> for a
        /// source that is not a camera.</summary>
        public unsafe ulong GetCameraValue(CameraValue which)
        {
            ulong value;
            FlatlineNative.flt_source_camera_value(LiveHandle, (int)which, &value);
            return value;
        }

        /// <summary>A GenICam integer (IntReg, MaskedIntReg, Integer, Boolean,
        /// Enumeration's value). <see cref="NotFoundException"/> names a
        /// feature the camera lacks or the client cannot resolve.</summary>
        public unsafe long GetInt(string feature)
        {
            long value;
            FlatlineNative.flt_source_get_int(LiveHandle, Feature(feature), &value);
            return value;
        }

        /// <summary>Writes a GenICam integer as is (the camera checks its range).</summary>
        public void SetInt(string feature, long value) =>
            FlatlineNative.flt_source_set_int(LiveHandle, Feature(feature), value);

        /// <summary>A GenICam float (Float, FloatReg, or an integer converted).</summary>
        public double GetFloat(string feature)
        {
            FlatlineNative.flt_source_get_float(LiveHandle, Feature(feature), out double value);
            return value;
        }

        public void SetFloat(string feature, double value) =>
            FlatlineNative.flt_source_set_float(LiveHandle, Feature(feature), value);

        /// <summary>Sets an enumeration by entry name ("Continuous").</summary>
        public void SetEnum(string feature, string entry)
        {
            if (entry == null)
                throw new ArgumentNullException(nameof(entry));
            FlatlineNative.flt_source_set_enum(LiveHandle, Feature(feature), entry);
        }

        /// <summary>Executes a command feature ("AcquisitionStart" ...).</summary>
        public void Execute(string feature) => FlatlineNative.flt_source_execute(LiveHandle, Feature(feature));

        /// <summary>Gives <paramref name="feature"/> a register instead of its
        /// XML node: <paramref name="length"/> bytes (1, 2, 4, 8) at
        /// <paramref name="address"/>, little-endian, unsigned or an IEEE float.</summary>
        public void MapFeature(string feature, ulong address, int length, bool isFloat = false)
        {
            if (length != 1 && length != 2 && length != 4 && length != 8)
                throw new ArgumentOutOfRangeException(nameof(length), length, "length must be 1, 2, 4 or 8 bytes");
            FlatlineNative.flt_source_map_feature(LiveHandle, Feature(feature), address, (uint)length, isFloat ? 1 : 0);
        }

        /// <summary>Reads <paramref name="bytes"/> bytes of camera memory through GenCP.</summary>
        public unsafe byte[] ReadMemory(ulong address, int bytes)
        {
            var live = LiveHandle;
            Shapes.AtLeast(bytes, 1, nameof(bytes));
            var data = new byte[bytes];
            fixed (byte* pd = data)
            {
                FlatlineNative.flt_source_read_memory(live, address, pd, (ulong)bytes);
            }
            return data;
        }

        /// <summary>Writes camera memory through GenCP.</summary>
        public unsafe void WriteMemory(ulong address, byte[] data)
        {
            var live = LiveHandle;
            if (data == null)
                throw new ArgumentNullException(nameof(data));
            if (data.Length == 0)
                throw new ArgumentException("data is empty", nameof(data));
            fixed (byte* pd = data)
            {
                FlatlineNative.flt_source_write_memory(live, address, pd, (ulong)data.Length);
            }
        }

        /// <summary>Stops a streaming camera, releases it and frees the native
        /// source now (then what it borrowed may go). Further calls throw
        /// <see cref="ObjectDisposedException"/>; a second Dispose does nothing.</summary>
        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }

        internal SourceHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(FrameSource));
                return handle;
            }
        }

        private static string Feature(string? feature) =>
            feature ?? throw new ArgumentNullException(nameof(feature));

        private static unsafe void CopyRows(byte* source, long stride, byte* target, int rowBytes, int rows)
        {
            for (int r = 0; r < rows; ++r)
                Buffer.MemoryCopy(source + r * stride, target + (long)r * rowBytes, rowBytes, rowBytes);
        }
    }
}
