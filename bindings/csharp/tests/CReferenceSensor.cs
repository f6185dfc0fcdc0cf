// SPDX-License-Identifier: Apache-2.0
using System;
using System.Runtime.InteropServices;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>
    /// The calibration and simulator C API called directly (no SWIG glue, no
    /// binding code), with flat row-major arrays indexed by hand
    /// ([i * 2 + c] for points, [r * fibers + k] for rows). The library
    /// resolver is registered in AgreementTests.cs.
    /// </summary>
    internal static unsafe partial class CReference
    {
        [DllImport(Core)] private static extern int flt_calib_create_reference(uint firstRow, uint rows, double firstX,
            double pitch, UIntPtr fibers, out IntPtr calib);
        [DllImport(Core)] private static extern void flt_calib_destroy(IntPtr calib);
        [DllImport(Core)] private static extern int flt_calib_image_to_plane(IntPtr calib, uint laser, UIntPtr count,
            double* image, double* plane);
        [DllImport(Core)] private static extern int flt_calib_plane_to_image(IntPtr calib, uint laser, UIntPtr count,
            double* plane, double* image);
        [DllImport(Core)] private static extern int flt_calib_undistort(IntPtr calib, UIntPtr count, double* image,
            double* undistorted);
        [DllImport(Core)] private static extern int flt_sim_create(IntPtr calib, IntPtr options, out IntPtr sim);
        [DllImport(Core)] private static extern void flt_sim_destroy(IntPtr sim);
        [DllImport(Core)] private static extern int flt_sim_add_defect(IntPtr sim, int kind, double amplitude, double period);
        [DllImport(Core)] private static extern int flt_sim_next_rows(IntPtr sim, UIntPtr rows, UIntPtr fibers,
            double* encoder, double* s, double* height, double* slope, byte* valid, double* truth);
        [DllImport(Core)] private static extern int flt_sim_next_frame(IntPtr sim, void* frame, UIntPtr capacity,
            UIntPtr stride, double* encoder, UIntPtr fibers, double* truth, double* peakRows,
            UIntPtr peakRowsCount);

        /// <summary>The three mappings of the reference sensor (ROI rows
        /// firstRow .. firstRow + rows), each over the same flat points.</summary>
        public static (double[] toPlane, double[] toImage, double[] undistorted) Map(
            uint firstRow, uint rows, uint laser, double[] imagePoints, double[] planePoints)
        {
            Ok(flt_calib_create_reference(firstRow, rows, -1000, 2, (UIntPtr)1001, out IntPtr calib));
            int n = imagePoints.Length / 2, m = planePoints.Length / 2;
            var toPlane = new double[2 * n];
            var undistorted = new double[2 * n];
            var toImage = new double[2 * m];
            fixed (double* pi = imagePoints, pp = planePoints, a = toPlane, b = toImage, c = undistorted)
            {
                Ok(flt_calib_image_to_plane(calib, laser, (UIntPtr)n, pi, a));
                Ok(flt_calib_plane_to_image(calib, laser, (UIntPtr)m, pp, b));
                Ok(flt_calib_undistort(calib, (UIntPtr)n, pi, c));
            }
            flt_calib_destroy(calib);
            return (toPlane, toImage, undistorted);
        }

        /// <summary>A simulator of the reference sensor (calib NULL: the
        /// whole 2048 x 2048 sensor, 1001 fibers) or of an ROI of it, with the
        /// given option values and one centre buckle of 12 mm over 1800 mm;
        /// then `blocks` calls of next_rows of `rows` rows each, and one frame.
        /// Flat [rows * fibers] arrays, concatenated over the blocks.</summary>
        public static (double[] e, double[] s, double[] h, double[] g, byte[] v, double[] truth, byte[] frame) Simulate(
            bool roi, (string name, double value)[] options, int blocks, int rows)
        {
            IntPtr calib = IntPtr.Zero;
            if (roi)
                Ok(flt_calib_create_reference(960, 128, -1000, 100, (UIntPtr)21, out calib));
            IntPtr bag = OptionsOf(options);
            Ok(flt_sim_create(calib, bag, out IntPtr sim));
            flt_options_destroy(bag);
            Ok(flt_sim_add_defect(sim, 1 /* FLT_SIM_CENTRE_BUCKLE */, 12, 1800));
            int fibers = roi ? 21 : 1001;
            int total = blocks * rows;
            var e = new double[total];
            var s = new double[total];
            var h = new double[total * fibers];
            var g = new double[total * fibers];
            var v = new byte[total * fibers];
            var truth = new double[total * fibers];
            fixed (double* pe = e, ps = s, ph = h, pg = g, pt = truth)
            fixed (byte* pv = v)
            {
                for (int b = 0; b < blocks; ++b)
                {
                    int first = b * rows;
                    Ok(flt_sim_next_rows(sim, (UIntPtr)rows, (UIntPtr)fibers, pe + first, ps + first,
                                         ph + first * fibers, pg + first * fibers, pv + first * fibers,
                                         pt + first * fibers));
                }
            }
            int width = 2048, height = roi ? 128 : 2048;
            var frame = new byte[width * height];
            fixed (byte* pf = frame)
            {
                Ok(flt_sim_next_frame(sim, pf, (UIntPtr)frame.Length, (UIntPtr)width, null, UIntPtr.Zero, null, null,
                                     UIntPtr.Zero));
            }
            flt_sim_destroy(sim);
            if (calib != IntPtr.Zero)
                flt_calib_destroy(calib);
            return (e, s, h, g, v, truth, frame);
        }

        private static IntPtr OptionsOf((string name, double value)[] options)
        {
            Ok(flt_options_create(out IntPtr bag));
            foreach (var (name, value) in options)
            {
                Ok(flt_option_find(System.Text.Encoding.ASCII.GetBytes(name + "\0"), out int key));
                Ok(flt_options_set(bag, key, value));
            }
            return bag;
        }
    }
}
