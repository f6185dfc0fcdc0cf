#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Generates the example dataset of examples/calibrate (committed in data/).

The reference sensor of tests/c/calib_synth.h in its 2x2-binned mode, so the
committed images stay small: 1024 x 1024 px of 11 um, f = 6 mm (545.45 px),
the same -15 % barrel distortion in the corners, mounted 1140 mm above the
strip and 1140 mm behind the lasers (45 degree triangulation), laser planes
at s = -50 and +50 mm.

  data/view_NN.png        10 chessboard views (9 x 6 inner corners, 60 mm
                          squares), 8-bit grey, 4x4 supersampled edges
  data/correspondences.csv  laser-plane target points and their raw image
                          points (0.05 px noise), plus the sensor geometry
  data/truth.txt          the camera the images were rendered with

Needs numpy only (PNG is written with zlib). Deterministic: run it again and
the files are byte-identical.
"""
import os
import struct
import sys
import zlib

import numpy as np

W = H = 1024
F = 6.0 / 0.011
CX, CY = 515.25, 509.75
DIST = (-0.08, 0.012, 1.5e-4, -1.0e-4, -0.002)  # k1 k2 p1 p2 k3
CAM_H = 1140.0
LASER_OFFSET = (-50.0, 50.0)
SQUARES = (10, 7)
SQUARE_MM = 60.0
POSES = [  # rx, ry, rz (deg), board centre in the camera frame (mm)
    (0, 0, 0, 0, 0, 1000), (25, 0, 0, 0, -300, 1100), (-25, 0, 0, 0, 300, 1100),
    (0, 25, 0, -350, 0, 1100), (0, -25, 0, 350, 0, 1100),
    (20, 20, 10, -400, -350, 1200), (-20, 20, -10, -400, 350, 1200),
    (20, -20, 5, 400, -350, 1200), (-20, -20, -5, 400, 350, 1200),
    (35, 0, 15, 0, 0, 1300),
]


def distort(x, y):
    k1, k2, p1, p2, k3 = DIST
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return xd, yd


def undistort(xd, yd):
    # Fixed-point iteration; contracts by ~0.3 per step at the corners.
    k1, k2, p1, p2, k3 = DIST
    x, y = xd.copy(), yd.copy()
    for _ in range(60):
        r2 = x * x + y * y
        radial = 1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3
        x = (xd - 2 * p1 * x * y - p2 * (r2 + 2 * x * x)) / radial
        y = (yd - p1 * (r2 + 2 * y * y) - 2 * p2 * x * y) / radial
    return x, y


def rotation(rx, ry, rz):
    cx, sx, cy, sy, cz, sz = (np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry),
                              np.cos(rz), np.sin(rz))
    rxm = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    rym = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rzm = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rzm @ rym @ rxm


def render(rays, pose):
    rx, ry, rz, tx, ty, tz = pose
    r = rotation(*np.radians([rx, ry, rz]))
    w, h = SQUARES[0] * SQUARE_MM, SQUARES[1] * SQUARE_MM
    t = np.array([tx, ty, tz]) - r @ np.array([w / 2, h / 2, 0])
    g = np.column_stack([r[:, 0], r[:, 1], t])
    ginv = np.linalg.inv(g)
    q = np.einsum('ij,hwj->hwi', ginv, rays)
    bx, by = q[..., 0] / q[..., 2], q[..., 1] / q[..., 2]
    # Board coordinates change per pixel by these (forward differences,
    # the last column/row repeats its neighbour's).
    dxu = np.concatenate([bx[:, 1:] - bx[:, :-1], bx[:, -1:] - bx[:, -2:-1]], axis=1)
    dyu = np.concatenate([by[:, 1:] - by[:, :-1], by[:, -1:] - by[:, -2:-1]], axis=1)
    dxv = np.concatenate([bx[1:] - bx[:-1], bx[-1:] - bx[-2:-1]], axis=0)
    dyv = np.concatenate([by[1:] - by[:-1], by[-1:] - by[-2:-1]], axis=0)
    total = np.zeros_like(bx)
    sub = 4
    for a in range(sub):
        for b in range(sub):
            ou, ov = (a - (sub - 1) / 2) / sub, (b - (sub - 1) / 2) / sub
            x = bx + dxu * ou + dxv * ov
            y = by + dyu * ou + dyv * ov
            checker = ((np.floor(x / SQUARE_MM) + np.floor(y / SQUARE_MM)) % 2 == 1)
            level = np.where(checker, 210.0, 40.0)
            inside = (x >= 0) & (y >= 0) & (x < w) & (y < h)
            margin = (x >= -SQUARE_MM) & (y >= -SQUARE_MM) & (x <= w + SQUARE_MM) & \
                     (y <= h + SQUARE_MM)
            level = np.where(inside, level, np.where(margin, 210.0, 100.0))
            total += level
    img = np.rint(total / sub ** 2)
    img[q[..., 2] <= 0] = 100
    return img.astype(np.uint8)


def write_png(path, img):
    raw = b''.join(b'\x01' + bytes(np.concatenate([row[:1], np.diff(row.astype(np.int16)) % 256]).astype(np.uint8))
                   for row in img)  # PNG filter "Sub": runs compress well

    def chunk(tag, data):
        return struct.pack('>I', len(data)) + tag + data + \
            struct.pack('>I', zlib.crc32(tag + data) & 0xffffffff)
    png = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', img.shape[1],
                                                             img.shape[0], 8, 0, 0, 0, 0))
    png += chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b'')
    with open(path, 'wb') as f:
        f.write(png)


def project(x, s, z):
    r = 1 / np.sqrt(2)
    ps, pz = s + CAM_H, z - CAM_H
    xc, yc, zc = x, -r * ps - r * pz, r * ps - r * pz
    xd, yd = distort(xc / zc, yc / zc)
    return F * xd + CX, F * yd + CY


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'data')
    os.makedirs(out, exist_ok=True)
    u, v = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    x, y = undistort((u - CX) / F, (v - CY) / F)
    rays = np.stack([x, y, np.ones_like(x)], axis=-1)
    for i, pose in enumerate(POSES):
        write_png(os.path.join(out, 'view_%02d.png' % i), render(rays, pose))

    rng = np.random.default_rng(20240601)
    with open(os.path.join(out, 'correspondences.csv'), 'w') as f:
        f.write('# Laser-plane calibration of the binned reference sensor '
                '(examples/calibrate/make_dataset.py).\n')
        f.write('# target chessboard 9 6 60\n')
        f.write('# frame 1024 1024\n')
        f.write('# laser_offset_mm -50 50\n')
        f.write('# encoder_mm_per_count 0.0125\n')
        f.write('# fibers -1000 2 1001\n')
        f.write('laser,u_px,v_px,x_mm,z_mm\n')
        for laser in (0, 1):
            for z in np.arange(-100, 101, 50.0):
                for xx in np.arange(-1200, 1201, 100.0):
                    uu, vv = project(xx, LASER_OFFSET[laser], z)
                    uu += 0.05 * rng.standard_normal()
                    vv += 0.05 * rng.standard_normal()
                    f.write('%d,%.4f,%.4f,%g,%g\n' % (laser, uu, vv, xx, z))
    with open(os.path.join(out, 'truth.txt'), 'w') as f:
        f.write('fx fy cx cy = %.6f %.6f %.2f %.2f\n' % (F, F, CX, CY))
        f.write('k1 k2 p1 p2 k3 = %g %g %g %g %g\n' % DIST)
    return 0


if __name__ == '__main__':
    sys.exit(main())
