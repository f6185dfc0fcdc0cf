// SPDX-License-Identifier: Apache-2.0
using System;

namespace Flatline.Tests
{
    /// <summary>
    /// Chessboard views rendered through a small distortion-free pinhole
    /// camera, written here independently of the library: 800 x 600 px,
    /// fx = fy = 700 px, principal point (401.5, 297.25). The board has
    /// 10 x 7 squares of 30 mm (9 x 6 inner corners) and a white margin of
    /// one square on a grey background; each pixel averages 4 x 4 exact
    /// sub-samples, so edges are anti-aliased to 1/16 px before 8-bit
    /// rounding.
    /// </summary>
    internal static class Chessboard
    {
        public const int Width = 800, Height = 600;
        public const double Focal = 700.0, Cx = 401.5, Cy = 297.25;
        public const int SquaresX = 10, SquaresY = 7;
        public const double SquareMm = 30.0;
        private const int Sub = 4;

        /// <summary>rx, ry, rz (degrees, about the board's own axes, applied
        /// x then y then z) and the board centre in the camera frame (mm):
        /// tilts of 20..35 degrees about both axes and boards off-centre, so
        /// the focal length and principal point are observable.</summary>
        public static readonly double[][] Poses =
        {
            new double[] { 0, 0, 0, 0, 0, 600 },
            new double[] { 25, 0, 0, 0, -60, 650 },
            new double[] { -25, 0, 0, 0, 60, 650 },
            new double[] { 0, 25, 0, -80, 0, 650 },
            new double[] { 0, -25, 0, 80, 0, 650 },
            new double[] { 20, 20, 10, -70, -50, 700 },
            new double[] { -20, 20, -10, -70, 50, 700 },
            new double[] { 20, -20, 5, 70, -50, 700 },
            new double[] { -20, -20, -5, 70, 50, 700 },
            new double[] { 35, 0, 15, 0, 0, 750 },
        };

        public static byte[,] Render(double[] pose)
        {
            const double deg = Math.PI / 180;
            double[] r = Rotation(pose[0] * deg, pose[1] * deg, pose[2] * deg);
            double w = SquaresX * SquareMm, h = SquaresY * SquareMm;
            // Board (X, Y, 1) -> camera (x, y, z): G = [r1 r2 t0], with the
            // board's origin at its centre t minus R (w/2, h/2, 0).
            var g = new double[9]
            {
                r[0], r[1], pose[3] - r[0] * w / 2 - r[1] * h / 2,
                r[3], r[4], pose[4] - r[3] * w / 2 - r[4] * h / 2,
                r[6], r[7], pose[5] - r[6] * w / 2 - r[7] * h / 2,
            };
            // Every corner of the margin must be in the image.
            for (int k = 0; k < 4; ++k)
            {
                double bx = (k & 1) != 0 ? w + SquareMm : -SquareMm, by = (k & 2) != 0 ? h + SquareMm : -SquareMm;
                double x = g[0] * bx + g[1] * by + g[2], y = g[3] * bx + g[4] * by + g[5], z = g[6] * bx + g[7] * by + g[8];
                double u = Focal * x / z + Cx, v = Focal * y / z + Cy;
                if (z <= 0 || u < 2 || v < 2 || u > Width - 3 || v > Height - 3)
                    throw new InvalidOperationException($"pose {string.Join(",", pose)} leaves the image");
            }
            double[] inverse = Inverse(g);
            var image = new byte[Height, Width];
            for (int v = 0; v < Height; ++v)
                for (int u = 0; u < Width; ++u)
                {
                    double sum = 0;
                    for (int a = 0; a < Sub; ++a)
                        for (int b = 0; b < Sub; ++b)
                        {
                            double ray_x = (u + (a - (Sub - 1) / 2.0) / Sub - Cx) / Focal;
                            double ray_y = (v + (b - (Sub - 1) / 2.0) / Sub - Cy) / Focal;
                            double X = inverse[0] * ray_x + inverse[1] * ray_y + inverse[2];
                            double Y = inverse[3] * ray_x + inverse[4] * ray_y + inverse[5];
                            double W = inverse[6] * ray_x + inverse[7] * ray_y + inverse[8];
                            X /= W;
                            Y /= W;
                            double level;
                            if (W <= 0 || X < -SquareMm || Y < -SquareMm || X > w + SquareMm || Y > h + SquareMm)
                                level = 100;  // background
                            else if (X < 0 || Y < 0 || X >= w || Y >= h)
                                level = 210;  // white margin
                            else
                                level = (((int)Math.Floor(X / SquareMm) + (int)Math.Floor(Y / SquareMm)) & 1) != 0 ? 210 : 40;
                            sum += level;
                        }
                    image[v, u] = (byte)Math.Round(sum / (Sub * Sub));
                }
            return image;
        }

        private static double[] Rotation(double rx, double ry, double rz)
        {
            double cx = Math.Cos(rx), sx = Math.Sin(rx), cy = Math.Cos(ry), sy = Math.Sin(ry),
                   cz = Math.Cos(rz), sz = Math.Sin(rz);
            // R = Rz Ry Rx
            return new[]
            {
                cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx,
                sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx,
                -sy, cy * sx, cy * cx,
            };
        }

        private static double[] Inverse(double[] m)
        {
            double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                         m[2] * (m[3] * m[7] - m[4] * m[6]);
            return new[]
            {
                (m[4] * m[8] - m[5] * m[7]) / det, (m[2] * m[7] - m[1] * m[8]) / det, (m[1] * m[5] - m[2] * m[4]) / det,
                (m[5] * m[6] - m[3] * m[8]) / det, (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det,
                (m[3] * m[7] - m[4] * m[6]) / det, (m[1] * m[6] - m[0] * m[7]) / det, (m[0] * m[4] - m[1] * m[3]) / det,
            };
        }
    }
}
