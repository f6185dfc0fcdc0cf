// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.Runtime.InteropServices;
using System.Text;

namespace Flatline
{
    /// <summary>Calibration target kinds (flt_calib_target in flatline/calib.h).</summary>
    public enum CalibrationTarget
    {
        /// <summary>Chessboard; columns x rows counts the <em>inner</em> corners.</summary>
        Chessboard = NativeTarget.FLT_TARGET_CHESSBOARD,
        /// <summary>Symmetric grid of dark circles on white; columns x rows circles.</summary>
        CircleGrid = NativeTarget.FLT_TARGET_CIRCLE_GRID,
        /// <summary>Asymmetric circle grid (OpenCV's layout); the pitch is the
        /// distance between neighbouring circles of one row divided by two.</summary>
        AsymmetricCircleGrid = NativeTarget.FLT_TARGET_ASYMMETRIC_CIRCLE_GRID,
    }

    /// <summary>
    /// Camera intrinsics in OpenCV's pinhole model: focal lengths
    /// <see cref="Fx"/>, <see cref="Fy"/> and principal point <see cref="Cx"/>,
    /// <see cref="Cy"/> in px (image frame: u right, v down, origin at the
    /// centre of the top-left pixel), radial distortion K1..K6 (K4..K6 are
    /// the rational terms, 0 unless estimated with
    /// <see cref="FlatlineOptions.CalibRationalDistortion"/>) and tangential
    /// P1, P2. Immutable; equal when every coefficient is equal.
    /// </summary>
    public sealed class CameraIntrinsics : IEquatable<CameraIntrinsics>
    {
        public CameraIntrinsics(double fx, double fy, double cx, double cy,
                                double k1 = 0, double k2 = 0, double p1 = 0, double p2 = 0,
                                double k3 = 0, double k4 = 0, double k5 = 0, double k6 = 0)
        {
            Fx = fx; Fy = fy; Cx = cx; Cy = cy;
            K1 = k1; K2 = k2; P1 = p1; P2 = p2; K3 = k3; K4 = k4; K5 = k5; K6 = k6;
        }

        /// <summary>From the C arrays: camera {fx, fy, cx, cy} and the 8
        /// distortion coefficients in OpenCV's order k1 k2 p1 p2 k3 k4 k5 k6.</summary>
        internal CameraIntrinsics(double[] camera, double[] d)
            : this(camera[0], camera[1], camera[2], camera[3], d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7]) { }

        public double Fx { get; }
        public double Fy { get; }
        public double Cx { get; }
        public double Cy { get; }
        public double K1 { get; }
        public double K2 { get; }
        public double K3 { get; }
        public double K4 { get; }
        public double K5 { get; }
        public double K6 { get; }
        public double P1 { get; }
        public double P2 { get; }

        /// <summary>{fx, fy, cx, cy}, px: the C layout.</summary>
        public double[] Camera => new[] { Fx, Fy, Cx, Cy };

        /// <summary>The 8 distortion coefficients in OpenCV's order
        /// k1 k2 p1 p2 k3 k4 k5 k6 (what cv::calibrateCamera returns).</summary>
        public double[] Distortion => new[] { K1, K2, P1, P2, K3, K4, K5, K6 };

        public bool Equals(CameraIntrinsics? other) =>
            other != null && Fx.Equals(other.Fx) && Fy.Equals(other.Fy) && Cx.Equals(other.Cx) &&
            Cy.Equals(other.Cy) && K1.Equals(other.K1) && K2.Equals(other.K2) && P1.Equals(other.P1) &&
            P2.Equals(other.P2) && K3.Equals(other.K3) && K4.Equals(other.K4) && K5.Equals(other.K5) &&
            K6.Equals(other.K6);

        public override bool Equals(object? obj) => Equals(obj as CameraIntrinsics);

        public override int GetHashCode()
        {
            int hash = 17;
            foreach (double v in new[] { Fx, Fy, Cx, Cy, K1, K2, P1, P2, K3, K4, K5, K6 })
                hash = hash * 31 + v.GetHashCode();
            return hash;
        }

        // Invariant: the same text under every culture, as calibration files.
        public override string ToString() =>
            FormattableString.Invariant(
                $"fx {Fx:R} fy {Fy:R} cx {Cx:R} cy {Cy:R} px; k1 {K1:R} k2 {K2:R} p1 {P1:R} p2 {P2:R} k3 {K3:R} k4 {K4:R} k5 {K5:R} k6 {K6:R}");
    }

    /// <summary>The fiber grid across the width: fiber k sits at
    /// x = FirstXMm + k * PitchMm (mm), k &lt; Count. Immutable.</summary>
    public sealed class FiberGrid : IEquatable<FiberGrid>
    {
        public FiberGrid(double firstXMm, double pitchMm, int count)
        {
            FirstXMm = firstXMm;
            PitchMm = pitchMm;
            Count = count;
        }

        public double FirstXMm { get; }
        public double PitchMm { get; }
        public int Count { get; }

        /// <summary>The x of fiber <paramref name="fiber"/>, mm.</summary>
        public double X(int fiber) => FirstXMm + fiber * PitchMm;

        public bool Equals(FiberGrid? other) =>
            other != null && FirstXMm.Equals(other.FirstXMm) && PitchMm.Equals(other.PitchMm) && Count == other.Count;

        public override bool Equals(object? obj) => Equals(obj as FiberGrid);
        public override int GetHashCode() => (FirstXMm.GetHashCode() * 31 + PitchMm.GetHashCode()) * 31 + Count;
        public override string ToString() =>
            FormattableString.Invariant($"{Count} fibers from x = {FirstXMm:R} mm every {PitchMm:R} mm");
    }

    /// <summary>What <see cref="Calibration.EstimateIntrinsics"/> measured.</summary>
    public sealed class IntrinsicsEstimate
    {
        internal IntrinsicsEstimate(CameraIntrinsics intrinsics, double rmsPx, double[] viewRmsPx)
        {
            Intrinsics = intrinsics;
            RmsPx = rmsPx;
            ViewRmsPx = viewRmsPx;
        }

        /// <summary>The estimate, now also stored in the calibration.</summary>
        public CameraIntrinsics Intrinsics { get; }
        /// <summary>Overall RMS reprojection error, px.</summary>
        public double RmsPx { get; }
        /// <summary>Per view (in the order given) its RMS reprojection error
        /// in px, NaN where the target was not found (the view was skipped).</summary>
        public double[] ViewRmsPx { get; }
        /// <summary>The views in which the target was found.</summary>
        public int ViewsUsed
        {
            get
            {
                int used = 0;
                foreach (double rms in ViewRmsPx)
                    if (!double.IsNaN(rms))
                        ++used;
                return used;
            }
        }
    }

    /// <summary>What <see cref="Calibration.EstimateHomography"/> measured.
    /// Per-point arrays are in the order of the correspondences.</summary>
    public sealed class HomographyEstimate
    {
        internal HomographyEstimate(double[,] homography, double rmsPx, double rmsMm,
                                    double[] residualPx, double[] residualMm, bool[] inlier)
        {
            Homography = homography;
            RmsPx = rmsPx;
            RmsMm = rmsMm;
            ResidualPx = residualPx;
            ResidualMm = residualMm;
            Inlier = inlier;
        }

        /// <summary>The estimate, now also stored in the calibration: [3, 3],
        /// maps undistorted (u, v, 1) px to the laser plane's (x, z, 1) mm.</summary>
        public double[,] Homography { get; }
        /// <summary>RMS over the inliers of <see cref="ResidualPx"/>, px.</summary>
        public double RmsPx { get; }
        /// <summary>RMS over the inliers of <see cref="ResidualMm"/>, mm.</summary>
        public double RmsMm { get; }
        /// <summary>Distance in px between each undistorted image point and
        /// its plane point mapped into the image through the estimate.</summary>
        public double[] ResidualPx { get; }
        /// <summary>Distance in mm between each image point mapped onto the
        /// plane and its plane point.</summary>
        public double[] ResidualMm { get; }
        /// <summary>True where the point was used in the final fit (all true
        /// without RANSAC).</summary>
        public bool[] Inlier { get; }
        /// <summary>The number of inliers.</summary>
        public int InlierCount => Array.FindAll(Inlier, x => x).Length;
    }

    /// <summary>
    /// The calibration model of a dual-line-laser sensor (flt_calib): camera
    /// intrinsics and lens distortion, one homography per laser from
    /// undistorted image points to that laser plane's (x, z) mm, and the
    /// sensor geometry (frame size, laser offsets along travel, encoder
    /// scale, fiber grid). See include/flatline/calib.h for the model, the
    /// frames and the file format.
    /// </summary>
    /// <remarks>
    /// Life cycle: <c>new Calibration()</c> is empty and unfinished; fill it
    /// with the setters and the Estimate methods, then <see cref="Finish"/>
    /// checks that every part is present and freezes it. Mapping and saving
    /// need a finished model; setters on a finished one throw
    /// <see cref="FlatlineStateException"/>. <see cref="Load"/>,
    /// <see cref="Parse"/> and <see cref="Reference"/> return finished models.
    /// Threads: a finished calibration is immutable and may be used from any
    /// number of threads at once; an unfinished one from one thread at a time.
    /// Dispose frees the native memory at once; a finalizer frees it otherwise.
    /// </remarks>
    public sealed class Calibration : IDisposable
    {
        /// <summary>Number of lasers (and homographies) of the sensor: 0 and 1.</summary>
        public const int Lasers = FlatlineNative.FLT_CALIB_LASERS;
        /// <summary>The version of the file format <see cref="Save"/> writes.</summary>
        public const int FormatVersion = FlatlineNative.FLT_CALIB_FORMAT_VERSION;

        private readonly CalibHandle handle;

        static Calibration() => NativeLoader.EnsureLoaded();

        /// <summary>An empty, unfinished model.</summary>
        public Calibration()
        {
            FlatlineNative.flt_calib_create(out handle);
            handle.Track(0);
        }

        private Calibration(CalibHandle handle)
        {
            this.handle = handle;
            handle.Track(0);
        }

        /// <summary>A calibration over a handle the library made (a recording's).</summary>
        internal static Calibration FromHandle(CalibHandle handle) => new Calibration(handle);

        /// <summary>Reads a calibration file (UTF-8 JSON, calib.h "File
        /// format"); the model is finished. <see cref="FlatlineIOException"/>
        /// if the file cannot be read, <see cref="FlatlineFormatException"/>
        /// if it is malformed (the message names the field, e.g.
        /// "lasers[1].homography[4]").</summary>
        public static Calibration Load(string path)
        {
            if (path == null)
                throw new ArgumentNullException(nameof(path));
            NativeLoader.EnsureLoaded();
            FlatlineNative.flt_calib_load(path, out CalibHandle loaded);
            return new Calibration(loaded);
        }

        /// <summary>The same as <see cref="Load"/> from the file's text.</summary>
        public static Calibration Parse(string text)
        {
            if (text == null)
                throw new ArgumentNullException(nameof(text));
            NativeLoader.EnsureLoaded();
            FlatlineNative.flt_calib_load_text(text, (ulong)Encoding.UTF8.GetByteCount(text), out CalibHandle parsed);
            return new Calibration(parsed);
        }

        /// <summary>
        /// The reference sensor (docs/sensor.md) as a finished model
        /// (flt_calib_create_reference in flatline/sim.h): 2048 x 2048 camera,
        /// fx = fy = 1090.9 px, lasers at offsets -50 and +50 mm, encoder
        /// 0.01 mm per count. <paramref name="firstRow"/>, <paramref name="rows"/>:
        /// the rows read out (an ROI; 0, 2048 for the whole sensor; the lines
        /// lie near rows 996 and 1044 at z = 0). The fiber grid:
        /// <paramref name="fibers"/> fibers from <paramref name="firstXMm"/>
        /// every <paramref name="pitchMm"/> mm.
        /// </summary>
        public static Calibration Reference(int firstRow = 0, int rows = 2048, double firstXMm = -1000.0,
                                            double pitchMm = 2.0, int fibers = 1001)
        {
            Shapes.AtLeast(firstRow, 0, nameof(firstRow));
            Shapes.AtLeast(rows, 1, nameof(rows));
            Shapes.AtLeast(fibers, 1, nameof(fibers));
            NativeLoader.EnsureLoaded();
            FlatlineNative.flt_calib_create_reference((uint)firstRow, (uint)rows, firstXMm, pitchMm,
                                                      (ulong)fibers, out CalibHandle reference);
            return new Calibration(reference);
        }

        /// <summary>Writes the finished model to <paramref name="path"/>
        /// through a temporary file renamed into place.
        /// <see cref="FlatlineIOException"/> if it cannot be written,
        /// <see cref="FlatlineStateException"/> if unfinished.</summary>
        public void Save(string path)
        {
            if (path == null)
                throw new ArgumentNullException(nameof(path));
            FlatlineNative.flt_calib_save(LiveHandle, path);
        }

        /// <summary>The text <see cref="Save"/> writes (byte-identical to the
        /// file, decoded from UTF-8).</summary>
        public unsafe string ToText()
        {
            var live = LiveHandle;
            // The size first: capacity 0 answers FLT_ERR_BUFFER_FULL with the
            // length set, which is the expected answer here, not an error.
            int status = FlatlineNativePINVOKE.flt_calib_save_text(live, null, UIntPtr.Zero, out UIntPtr length);
            if (status != (int)Status.BufferFull)
                Errors.Check(status);
            var text = new byte[checked((int)length.ToUInt64() + 1)];
            fixed (byte* pt = text)
            {
                FlatlineNative.flt_calib_save_text(live, pt, (ulong)text.Length, out length);
            }
            return Encoding.UTF8.GetString(text, 0, (int)length.ToUInt64());
        }

        /// <summary>True once <see cref="Finish"/> succeeded (or for a loaded model).</summary>
        public bool IsFinished
        {
            get
            {
                FlatlineNative.flt_calib_is_finished(LiveHandle, out int finished);
                return finished != 0;
            }
        }

        /// <summary>Checks that intrinsics, frame size, both homographies,
        /// both (distinct) laser offsets, the encoder scale and the fiber grid
        /// are set, then freezes the model. <see cref="FlatlineStateException"/>
        /// naming the first missing part (the model stays unfinished), or if
        /// already finished.</summary>
        public void Finish() => FlatlineNative.flt_calib_finish(LiveHandle);

        /// <summary>The frame size in px (each 1 .. 65536). Needed before
        /// estimating intrinsics.</summary>
        public void SetFrameSize(int width, int height)
        {
            Shapes.AtLeast(width, 1, nameof(width));
            Shapes.AtLeast(height, 1, nameof(height));
            FlatlineNative.flt_calib_set_frame_size(LiveHandle, (uint)width, (uint)height);
        }

        /// <summary>The frame width, px. <see cref="FlatlineStateException"/> if not set.</summary>
        public int FrameWidth
        {
            get
            {
                FlatlineNative.flt_calib_get_frame_size(LiveHandle, out uint width, out _);
                return (int)width;
            }
        }

        /// <summary>The frame height, px. <see cref="FlatlineStateException"/> if not set.</summary>
        public int FrameHeight
        {
            get
            {
                FlatlineNative.flt_calib_get_frame_size(LiveHandle, out _, out uint height);
                return (int)height;
            }
        }

        /// <summary>The camera intrinsics. Get: <see cref="FlatlineStateException"/>
        /// if none are set. Set: copies them (fx, fy &gt; 0 and every value
        /// finite, else <see cref="InvalidArgumentException"/>).</summary>
        public unsafe CameraIntrinsics Intrinsics
        {
            get
            {
                var live = LiveHandle;
                var camera = new double[4];
                var distortion = new double[FlatlineNative.FLT_CALIB_DISTORTION_COEFFS];
                fixed (double* pc = camera, pd = distortion)
                {
                    FlatlineNative.flt_calib_get_intrinsics(live, pc, (ulong)camera.Length, pd, (ulong)distortion.Length);
                }
                return new CameraIntrinsics(camera, distortion);
            }
            set
            {
                if (value == null)
                    throw new ArgumentNullException(nameof(value));
                var live = LiveHandle;
                fixed (double* pc = value.Camera, pd = value.Distortion)
                {
                    FlatlineNative.flt_calib_set_intrinsics(live, pc, (ulong)value.Camera.Length, pd,
                                                            (ulong)value.Distortion.Length);
                }
            }
        }

        /// <summary>
        /// Estimates the intrinsics from images of a planar target (OpenCV's
        /// detection, sub-pixel refinement and calibrateCamera) and stores
        /// them. Every image is [FrameHeight, FrameWidth] (rows, columns) of
        /// 8-bit grey levels; the frame size must be set. <paramref name="columns"/>
        /// x <paramref name="rows"/>: the target's inner corners (chessboard)
        /// or circles; <paramref name="pitchMm"/>: square side or circle
        /// spacing, mm. <paramref name="options"/>: calib_rational_distortion.
        /// Views without a detected target are skipped (NaN in
        /// <see cref="IntrinsicsEstimate.ViewRmsPx"/>); fewer than 3 usable
        /// views is a <see cref="NumericException"/> and leaves the model
        /// unchanged. Wrong image sizes throw <see cref="ArgumentException"/>
        /// before the native call.
        /// </summary>
        public unsafe IntrinsicsEstimate EstimateIntrinsics(IReadOnlyList<byte[,]> images, CalibrationTarget target,
                                                            int columns, int rows, double pitchMm,
                                                            FlatlineOptions? options = null)
        {
            var live = LiveHandle;
            if (images == null)
                throw new ArgumentNullException(nameof(images));
            if (images.Count == 0)
                throw new ArgumentException("images is empty: give at least 3 views", nameof(images));
            Shapes.AtLeast(columns, 0, nameof(columns));
            Shapes.AtLeast(rows, 0, nameof(rows));
            // The frame size, when set, is what every image must have; when
            // not set, the C call names the missing frame size.
            bool sized = TryFrameSize(out int width, out int height);
            if (!sized)
            {
                if (images[0] == null)
                    throw new ArgumentNullException(nameof(images), "images[0] is null");
                height = images[0].GetLength(0);
                width = images[0].GetLength(1);
            }
            for (int v = 0; v < images.Count; ++v)
            {
                var image = images[v];
                if (image == null)
                    throw new ArgumentNullException(nameof(images), $"images[{v}] is null");
                if (image.GetLength(0) != height || image.GetLength(1) != width || width == 0 || height == 0)
                    throw new ArgumentException(
                        $"images[{v}] is [{image.GetLength(0)}, {image.GetLength(1)}] but must be " +
                        $"[{height}, {width}] (rows, columns: the {(sized ? "calibration's" : "first image's")} frame size)",
                        nameof(images));
            }
            var pins = new GCHandle[images.Count];
            var pointers = new IntPtr[images.Count];
            var viewRms = new double[images.Count];
            double rms = double.NaN;
            try
            {
                for (int v = 0; v < images.Count; ++v)
                {
                    pins[v] = GCHandle.Alloc(images[v], GCHandleType.Pinned);
                    pointers[v] = pins[v].AddrOfPinnedObject();
                }
                using (var scope = FlatlineOptions.Borrow(options))
                {
                    fixed (IntPtr* pp = pointers)
                    fixed (double* pv = viewRms)
                    {
                        FlatlineNative.flt_calib_estimate_intrinsics(live, (ulong)images.Count, pp, (ulong)width,
                                                                     (NativeTarget)target, (uint)columns, (uint)rows,
                                                                     pitchMm, scope.Handle, &rms, pv);
                    }
                }
            }
            finally
            {
                foreach (var pin in pins)
                    if (pin.IsAllocated)
                        pin.Free();
            }
            return new IntrinsicsEstimate(Intrinsics, rms, viewRms);
        }

        /// <summary>Laser <paramref name="laser"/>'s homography, [3, 3]
        /// row-major: undistorted (u, v, 1) px to (x, z, 1) mm.
        /// <see cref="FlatlineStateException"/> if not set.</summary>
        public unsafe double[,] GetHomography(int laser)
        {
            var live = LiveHandle;
            uint l = Shapes.Laser(laser);
            var h = new double[3, 3];
            fixed (double* ph = h)
            {
                FlatlineNative.flt_calib_get_homography(live, l, ph, (ulong)h.Length);
            }
            return h;
        }

        /// <summary>Sets laser <paramref name="laser"/>'s homography directly
        /// ([3, 3], finite and invertible, else <see cref="InvalidArgumentException"/>).</summary>
        public unsafe void SetHomography(int laser, double[,] homography)
        {
            var live = LiveHandle;
            uint l = Shapes.Laser(laser);
            if (homography == null)
                throw new ArgumentNullException(nameof(homography));
            if (homography.GetLength(0) != 3 || homography.GetLength(1) != 3)
                throw new ArgumentException(
                    $"homography is [{homography.GetLength(0)}, {homography.GetLength(1)}] but must be [3, 3]",
                    nameof(homography));
            fixed (double* ph = homography)
            {
                FlatlineNative.flt_calib_set_homography(live, l, ph, (ulong)homography.Length);
            }
        }

        /// <summary>
        /// Estimates laser <paramref name="laser"/>'s homography from
        /// correspondences and stores it (the intrinsics must be set: the
        /// image points are undistorted through them). <paramref name="imagePx"/>
        /// [count, 2] raw image points (u, v) px; <paramref name="planeMm"/>
        /// [count, 2] laser-plane points (x, z) mm. <paramref name="options"/>:
        /// calib_ransac, calib_ransac_threshold, calib_ransac_iterations,
        /// calib_ransac_seed (null: no RANSAC). Deterministic. A degenerate set
        /// is a <see cref="NumericException"/> and leaves the model unchanged.
        /// </summary>
        public unsafe HomographyEstimate EstimateHomography(int laser, double[,] imagePx, double[,] planeMm,
                                                            FlatlineOptions? options = null)
        {
            var live = LiveHandle;
            uint l = Shapes.Laser(laser);
            int count = Shapes.Points(imagePx, nameof(imagePx));
            Shapes.Check(planeMm, count, 2, nameof(planeMm));
            var residualPx = new double[count];
            var residualMm = new double[count];
            var inlier = new bool[count];
            double rmsPx, rmsMm;
            using (var scope = FlatlineOptions.Borrow(options))
            {
                fixed (double* pi = imagePx, pp = planeMm, rp = residualPx, rm = residualMm)
                fixed (bool* pin = inlier)
                {
                    FlatlineNative.flt_calib_estimate_homography(live, l, (ulong)count, pi, pp, scope.Handle,
                                                                 rp, rm, (byte*)pin, &rmsPx, &rmsMm);
                }
            }
            return new HomographyEstimate(GetHomography(laser), rmsPx, rmsMm, residualPx, residualMm, inlier);
        }

        /// <summary>Laser <paramref name="laser"/>'s offset along travel, mm:
        /// at encoder reading e it sees material s = e - offset.
        /// <see cref="FlatlineStateException"/> if not set.</summary>
        public double GetLaserOffset(int laser)
        {
            var live = LiveHandle;
            FlatlineNative.flt_calib_get_laser_offset(live, Shapes.Laser(laser), out double offset);
            return offset;
        }

        /// <summary>Sets laser <paramref name="laser"/>'s offset along travel, mm (finite).</summary>
        public void SetLaserOffset(int laser, double offsetMm)
        {
            var live = LiveHandle;
            FlatlineNative.flt_calib_set_laser_offset(live, Shapes.Laser(laser), offsetMm);
        }

        /// <summary>Delta-d = offset of laser 1 - offset of laser 0, mm.
        /// <see cref="FlatlineStateException"/> unless both are set.</summary>
        public double LaserSpacing
        {
            get
            {
                FlatlineNative.flt_calib_laser_spacing(LiveHandle, out double spacing);
                return spacing;
            }
        }

        /// <summary>The encoder scale, mm of travel per count (finite,
        /// non-zero; negative when the encoder counts down).</summary>
        public double EncoderScale
        {
            get
            {
                FlatlineNative.flt_calib_get_encoder_scale(LiveHandle, out double scale);
                return scale;
            }
            set => FlatlineNative.flt_calib_set_encoder_scale(LiveHandle, value);
        }

        /// <summary>The fiber grid across the width (pitch &gt; 0, count
        /// &gt;= 1, all finite). Get: <see cref="FlatlineStateException"/> if not set.</summary>
        public unsafe FiberGrid FiberGrid
        {
            get
            {
                var live = LiveHandle;
                double first, pitch;
                FlatlineNative.flt_calib_get_fiber_grid(live, &first, &pitch, out UIntPtr count);
                return new FiberGrid(first, pitch, checked((int)count.ToUInt64()));
            }
            set
            {
                if (value == null)
                    throw new ArgumentNullException(nameof(value));
                var live = LiveHandle;
                Shapes.AtLeast(value.Count, 0, "value.Count");
                FlatlineNative.flt_calib_set_fiber_grid(live, value.FirstXMm, value.PitchMm, (ulong)value.Count);
            }
        }

        /// <summary>Raw image points [count, 2] (u, v) px to laser
        /// <paramref name="laser"/>'s plane, [count, 2] (x, z) mm. A NaN
        /// point maps to NaN. Finished model only; thread-safe.</summary>
        public unsafe double[,] ImageToPlane(int laser, double[,] imagePx)
        {
            var live = LiveHandle;
            uint l = Shapes.Laser(laser);
            int count = Shapes.Points(imagePx, nameof(imagePx));
            var plane = new double[count, 2];
            fixed (double* pi = imagePx, pp = plane)
            {
                FlatlineNative.flt_calib_image_to_plane(live, l, (ulong)count, pi, pp);
            }
            return plane;
        }

        /// <summary>Laser-plane points [count, 2] (x, z) mm to raw image
        /// points [count, 2] (u, v) px (NaN behind the camera). Finished model only.</summary>
        public unsafe double[,] PlaneToImage(int laser, double[,] planeMm)
        {
            var live = LiveHandle;
            uint l = Shapes.Laser(laser);
            int count = Shapes.Points(planeMm, nameof(planeMm));
            var image = new double[count, 2];
            fixed (double* pp = planeMm, pi = image)
            {
                FlatlineNative.flt_calib_plane_to_image(live, l, (ulong)count, pp, pi);
            }
            return image;
        }

        /// <summary>Raw image points [count, 2] px to undistorted image points
        /// [count, 2] px (NaN where the inverse does not converge). Needs only
        /// the intrinsics.</summary>
        public unsafe double[,] Undistort(double[,] imagePx)
        {
            var live = LiveHandle;
            int count = Shapes.Points(imagePx, nameof(imagePx));
            var undistorted = new double[count, 2];
            fixed (double* pi = imagePx, pu = undistorted)
            {
                FlatlineNative.flt_calib_undistort(live, (ulong)count, pi, pu);
            }
            return undistorted;
        }

        /// <summary>Frees the native model now. Further calls throw
        /// <see cref="ObjectDisposedException"/>; a second Dispose does nothing.
        /// Objects created from this calibration (a <see cref="SimulatedLine"/>)
        /// copied it and keep working.</summary>
        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }

        internal CalibHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(Calibration));
                return handle;
            }
        }

        private bool TryFrameSize(out int width, out int height)
        {
            width = height = 0;
            try
            {
                FlatlineNative.flt_calib_get_frame_size(LiveHandle, out uint w, out uint h);
                width = (int)w;
                height = (int)h;
                return true;
            }
            catch (FlatlineStateException)
            {
                return false;
            }
        }
    }
}
