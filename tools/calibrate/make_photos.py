#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Renders the laser photos flatline-calibrate's test calibrates from.

The camera and the sensor are examples/calibrate's (make_dataset.py: the
reference sensor binned 2x2, 1024 x 1024 px, f = 545.45 px, mounted
1140 mm above the pass line and 1140 mm behind the lasers, looking down at
45 degrees); the board photos for the intrinsics are that example's
committed views. Here a 13 x 8-square chessboard of 100 mm squares
(12 x 7 inner corners: an even and an odd count, so that its corners are never read turned by 180 degrees) lies in 8 poses under the lasers, the first flat on the pass line with its
x axis across the strip (the reference), the others raised, lowered and
tilted. The intrinsics' photos:

  intrinsics/view_NN.png  12 views of the 10 x 7-square board of 60 mm
                      squares over the whole field of view

and per pose of the laser board three photos:

  boards/pose_N.png   the board alone
  laser0/pose_N.png   the board with laser 0's line (plane s = -50 mm)
  laser1/pose_N.png   the board with laser 1's line (plane s = +50 mm)

The line is a Gaussian across the laser plane (sigma 4 mm, about one
pixel at this distance) added to the board's grey, 4 x 4 samples per
pixel (from the rays through the pixel centres and the board coordinates'
change from pixel to pixel: the lens is undistorted once). truth.json holds the camera and the laser planes in the camera's
frame. Deterministic; needs numpy only.

    make_photos.py OUT_DIR
"""

import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "examples", "calibrate"))
import make_dataset as cam  # noqa: E402  (the camera: W, H, F, CX, CY, DIST)

R2 = 1 / np.sqrt(2)
# world (x across, s along travel, z up) -> camera: P_cam = M P_world + C
M = np.array([[1.0, 0.0, 0.0], [0.0, -R2, -R2], [0.0, R2, -R2]])
C = np.array([0.0, 0.0, 2 * R2 * cam.CAM_H])
LASER_S = cam.LASER_OFFSET  # the planes s = -50 and s = +50 mm
SIGMA_MM = 4.0
LINE_PEAK = 100.0
# The board under the lasers: larger than the intrinsics' board, so that
# the lines span most of the field of view (--laser-target
# chessboard:12x7:100).
SQUARE = 100.0
SQUARES = (13, 8)
BOARD_W, BOARD_H = SQUARES[0] * SQUARE, SQUARES[1] * SQUARE
# The intrinsics' photos: examples/calibrate's board (10 x 7 squares of
# 60 mm, --target chessboard:9x6:60) rendered by make_dataset.render in
# poses of the camera's frame (rx, ry, rz degrees; board centre mm) that
# reach every part of the field of view, so that the lens is known where
# the lines fall.
INTRINSICS_POSES = [
    (30, 25, 5, -540, -540, 1150), (-30, 20, -5, 0, -580, 1150), (30, -25, 5, 540, -540, 1150),
    (25, 30, 0, -600, 0, 1150), (0, 0, 0, 0, 0, 1000), (-25, -30, 0, 600, 0, 1150),
    (-30, 25, 10, -540, 540, 1150), (30, -20, -10, 0, 580, 1150), (-30, -25, 5, 540, 540, 1150),
    (35, 0, 15, -300, -300, 1300), (-35, 0, -15, 300, 300, 1300), (0, 35, 10, 0, 0, 1250),
]
# The laser photos' board: x, s, z of its centre (mm); roll about s, pitch
# about x, yaw about z (degrees)
POSES = [
    (0, 0, 0, 0, 0, 0),
    (60, 0, 50, 0, 0, 0),
    (0, 10, -40, 8, 0, 0),
    (-50, -10, 20, 0, 15, 0),
    (40, 0, 80, -6, -12, 0),
    (0, 5, -60, 0, 10, 6),
    (-60, 0, 30, 8, 0, 0),
    (50, -5, 0, 0, -20, -5),
]


def rotation(roll, pitch, yaw):
    a, b, c = np.radians([pitch, roll, yaw])
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    rs = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rz @ rs @ rx


def render(pose, rays_world, eye, sub=4, square=SQUARE, squares=SQUARES):  # noqa: C901
    """(board, line0, line1): the board's grey and each laser's line
    intensity, (H, W), each the mean of sub x sub samples per pixel (the
    sample points from the pixel centre's board and strip coordinates and
    their change from pixel to pixel)."""
    x, s, z, roll, pitch, yaw = pose
    r = rotation(roll, pitch, yaw)
    u, v, n = r[:, 0], r[:, 1], r[:, 2]
    board_w, board_h = squares[0] * square, squares[1] * square
    origin = np.array([x, s, z]) - u * board_w / 2 - v * board_h / 2
    t = ((origin - eye) @ n) / (rays_world @ n)
    p = eye + t[..., None] * rays_world
    coords = [(p - origin) @ u, (p - origin) @ v, p[..., 1]]  # board x, y; strip s

    def steps(a):
        du = np.concatenate([a[:, 1:] - a[:, :-1], a[:, -1:] - a[:, -2:-1]], axis=1)
        dv = np.concatenate([a[1:] - a[:-1], a[-1:] - a[-2:-1]], axis=0)
        return du, dv

    d = [steps(a) for a in coords]
    grey = np.zeros(t.shape)
    lines = [np.zeros(t.shape), np.zeros(t.shape)]
    for i in range(sub):
        for j in range(sub):
            ou, ov = (i - (sub - 1) / 2) / sub, (j - (sub - 1) / 2) / sub
            bx, by, ss = (a + da * ou + dv * ov for a, (da, dv) in zip(coords, d))
            checker = (np.floor(bx / square) + np.floor(by / square)) % 2 == 1
            inside = (bx >= 0) & (by >= 0) & (bx < board_w) & (by < board_h)
            margin = (bx >= -square) & (by >= -square) & (bx <= board_w + square) & \
                (by <= board_h + square) & (t > 0)
            grey += np.where(inside, np.where(checker, 150.0, 30.0),
                             np.where(margin, 150.0, 60.0))
            for k, s_l in enumerate(LASER_S):
                lines[k] += np.where(margin,
                                     LINE_PEAK * np.exp(-0.5 * ((ss - s_l) / SIGMA_MM) ** 2), 0.0)
    return grey / sub ** 2, lines[0] / sub ** 2, lines[1] / sub ** 2


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "calibrate-photos"
    for sub in ("intrinsics", "boards", "laser0", "laser1"):
        os.makedirs(os.path.join(out, sub), exist_ok=True)
    eye = -M.T @ C  # the camera's centre in the world
    uu, vv = np.meshgrid(np.arange(cam.W, dtype=float), np.arange(cam.H, dtype=float))
    xn, yn = cam.undistort((uu - cam.CX) / cam.F, (vv - cam.CY) / cam.F)
    rays = np.stack([xn, yn, np.ones_like(xn)], axis=-1) @ M  # rows: M.T @ ray
    camera_rays = np.stack([xn, yn, np.ones_like(xn)], axis=-1)
    for i, pose in enumerate(INTRINSICS_POSES):
        cam.write_png(os.path.join(out, "intrinsics", "view_%02d.png" % i),
                      cam.render(camera_rays, pose))
    for i, pose in enumerate(POSES):
        board, line0, line1 = render(pose, rays, eye)
        for name, image in (("boards", board), ("laser0", board + line0),
                            ("laser1", board + line1)):
            cam.write_png(os.path.join(out, name, "pose_%d.png" % i),
                          np.clip(np.rint(image), 0, 255).astype(np.uint8))
    truth = {
        "camera": {"fx": cam.F, "fy": cam.F, "cx": cam.CX, "cy": cam.CY,
                   "distortion": list(cam.DIST)},
        # plane n . P_cam = d per laser, n unit, in the camera frame
        "lasers": [{"normal": list(M @ np.array([0.0, 1.0, 0.0])),
                    "d": float((M @ np.array([0.0, 1.0, 0.0])) @ C + s_l)} for s_l in LASER_S],
        "spacing_mm": LASER_S[1] - LASER_S[0],
    }
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
