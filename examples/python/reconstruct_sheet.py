#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Simulates the reference sheet with libflatline's simulated sensor,
reconstructs it, and plots raw against reconstructed heights to PNG files.

The sheet (after the reference article, see README.md): centre buckles and wavy edges,
sinusoidal along travel with period 1800 mm and 12 mm amplitude, 9000 mm
long, measured every 3 mm of travel, fibers every 10 mm across 1500 mm. The
sensor is the reference one (flatline.Calibration.reference(): two laser
lines 100 mm apart, a 2048 x 2048 camera at 45 degrees). The simulator
(flatline.SimulatedLine) gives what the two lasers measure, with the strip
bouncing by N(0, 2.5 mm) per frame (both lasers, every fiber: it leaves the
slope untouched) and 1/16 px of peak-detection noise per laser and fiber:
    height = (z(s - 50) + z(s + 50)) / 2,   slope = (z(s + 50) - z(s - 50)) / 100

It reconstructs twice: the whole sheet at once (flatline.reconstruct) and
on the line: the rows go one by one into a flatline.Gauge with the shear's
cuts every 3000 mm, and the gauge hands out finished sheets, each with its
shape class, I-Unit zone profile and height map. It prints the accuracy of
both against the simulator's ground truth and each sheet's results, and
plots the zone profiles. It also renders one camera frame and finds the two
laser lines in it with flatline.Extractor, as the gauge's workers do per
frame (a gauge takes camera frames with push_frame the same way).

Usage:
    python3 examples/python/reconstruct_sheet.py [--out DIR] [--seed N]
With the package built by CMake (not installed), point PYTHONPATH at it:
    PYTHONPATH=build/dev/bindings/python/package python3 examples/python/reconstruct_sheet.py
"""

import argparse
import os
import time

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import flatline  # noqa: E402

LENGTH = 9000.0  # mm of sheet along travel
STEP = 3.0  # mm of travel between frames
WIDTH = 1500.0  # mm across
PITCH = 10.0  # mm between fibers
VIBRATION = 2.5  # mm, sigma of the strip's bounce per frame
PEAK_NOISE = 1 / 16  # px, sigma of one laser's peak per fiber
CUT_EVERY = 3000.0  # mm of strip between the shear's cuts


def simulate(seed):
    """Rows (s, height, slope) and the truth from the simulated sensor, and
    one rendered camera frame with the peaks the extractor finds in it."""
    fibers = int(round(WIDTH / PITCH)) + 1
    calib = flatline.Calibration.reference(first_x_mm=-WIDTH / 2, pitch_mm=PITCH,
                                           fibers=fibers)
    with flatline.SimulatedLine(calib, sim_seed=seed, sim_frame_spacing=STEP,
                                sim_strip_width=WIDTH, sim_heave_sigma=VIBRATION,
                                sim_peak_sigma=PEAK_NOISE) as sim, \
            flatline.Extractor(calib) as extractor:
        sim.add_defect(flatline.Defect.CENTRE_BUCKLE, 12.0, 1800.0)
        sim.add_defect(flatline.Defect.WAVY_EDGE_BOTH, 12.0, 1800.0)
        rows = sim.next_rows(int(LENGTH / STEP))
        frame = sim.next_frame()
        peaks = extractor.peaks(frame.image)
    return calib, rows, frame, peaks


def on_the_line(calib, s, height, slope):
    """The on-line way: one Gauge takes the profile rows at their encoder
    positions (a sensor that extracts its own profiles; camera frames go in
    with push_frame) and the shear's cuts, and hands out each sheet once the
    reconstructor has seen enough strip beyond its cut. The gauge takes the
    fibers and the laser spacing from the calibration."""
    centre = sum(calib.laser_offsets) / 2  # the row at s: the frame at encoder s + centre
    sheets = []
    with flatline.Gauge(calib, rigid_motion=1, gauge_frame_spacing=0.8 * STEP,
                        gauge_overflow=1, gauge_keep_maps=1) as gauge:
        for cut in np.arange(CUT_EVERY, s[-1], CUT_EVERY):
            gauge.cut(cut + centre)
        for r in range(len(s)):
            gauge.push_row(s[r] + centre, height[r], slope[r])
            sheets.extend(gauge)  # the sheets finished so far
        gauge.flush()  # the end of the strip: its last sheet
        sheets.extend(gauge)
    assert np.array_equal(np.concatenate([sheet.s for sheet in sheets]), s)
    return sheets


def stats(error):
    return (f"max {np.abs(error).max():.3f} mm, RMSE {np.sqrt(np.mean(error ** 2)):.3f} mm, "
            f"std {error.std():.3f} mm")


def plot(out_dir, s, x, height, z, z_true, fiber):
    extent = [x[0], x[-1], s[-1] / 1000, s[0] / 1000]  # width mm, travel m
    limit = max(np.abs(height).max(), np.abs(z).max())
    fig, axes = plt.subplots(1, 3, figsize=(13, 6), sharey=True, constrained_layout=True)
    error = z - z_true
    panels = [(height, "raw heights (mean of the lasers)", limit, "z [mm]"),
              (z, "reconstructed (the gauge's sheets)", limit, "z [mm]"),
              (error, "reconstructed - true", np.abs(error).max(), "error [mm]")]
    for ax, (image, title, scale, label) in zip(axes, panels):
        im = ax.imshow(image, aspect="auto", extent=extent, cmap="RdBu_r",
                       vmin=-scale, vmax=scale, interpolation="nearest")
        ax.set_title(title)
        ax.set_xlabel("x across the width [mm]")
        fig.colorbar(im, ax=ax, shrink=0.8, label=label)
    axes[0].set_ylabel("s along travel [m]")
    fig.suptitle(f"Reference sheet {LENGTH / 1000:.0f} m x {WIDTH:.0f} mm, "
                 f"vibration {VIBRATION} mm, peak noise {PEAK_NOISE:.4g} px")
    heights_png = os.path.join(out_dir, "heights.png")
    fig.savefig(heights_png, dpi=110)
    plt.close(fig)

    fig, (ax, ax_err) = plt.subplots(2, 1, figsize=(12, 7), sharex=True,
                                     gridspec_kw={"height_ratios": [3, 1]},
                                     constrained_layout=True)
    ax.plot(s / 1000, height[:, fiber], lw=0.6, color="0.65", label="raw height")
    ax.plot(s / 1000, z_true[:, fiber], lw=2.5, color="tab:green", label="true")
    ax.plot(s / 1000, z[:, fiber], lw=1.2, color="tab:red", ls="--", label="reconstructed")
    ax.set_ylabel("z [mm]")
    ax.set_title(f"fiber at x = {x[fiber]:.0f} mm")
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3)
    ax_err.plot(s / 1000, z[:, fiber] - z_true[:, fiber], lw=0.8, color="tab:red")
    ax_err.set_ylabel("reconstructed - true [mm]")
    ax_err.set_xlabel("s along travel [m]")
    ax_err.grid(alpha=0.3)
    fiber_png = os.path.join(out_dir, "fiber.png")
    fig.savefig(fiber_png, dpi=110)
    plt.close(fig)
    return heights_png, fiber_png


def plot_zones(out_dir, sheets):
    """Each sheet's I-Unit profile across the width, as the operator reads it."""
    fig, axes = plt.subplots(len(sheets), 1, figsize=(11, 2.4 * len(sheets)), sharex=True,
                             sharey=True, constrained_layout=True, squeeze=False)
    for ax, sheet in zip(axes[:, 0], sheets):
        zones = sheet.zones
        ax.bar(zones.centre_x, np.nan_to_num(zones.i_units), width=0.85 * np.diff(zones.centre_x)[0],
               color="tab:blue")
        ax.set_ylabel("I-Units")
        ax.set_title(f"sheet {sheet.id} ({sheet.s_start / 1000:.1f}-{sheet.s_end / 1000:.1f} m): "
                     f"{sheet.shape}, confidence {sheet.confidence:.2f}", fontsize=10)
        ax.grid(alpha=0.3, axis="y")
    axes[-1, 0].set_xlabel("zone centre across the width [mm]")
    zones_png = os.path.join(out_dir, "zones.png")
    fig.savefig(zones_png, dpi=110)
    plt.close(fig)
    return zones_png


def plot_frame(out_dir, frame, peaks):
    """The rendered camera frame around the two lines, with the sub-pixel
    peak rows the extractor found (every 8th column, to keep them visible)."""
    centre = int(np.nanmedian(peaks))
    top, bottom = max(centre - 60, 0), min(centre + 60, frame.image.shape[0])
    columns = np.arange(frame.image.shape[1])
    fig, ax = plt.subplots(figsize=(12, 4), constrained_layout=True)
    ax.imshow(frame.image[top:bottom], cmap="gray", aspect="auto",
              extent=[-0.5, columns[-1] + 0.5, bottom - 0.5, top - 0.5])
    for laser, colour in ((0, "tab:red"), (1, "tab:cyan")):
        ax.plot(columns[::8], peaks[laser, ::8], ".", ms=2, color=colour,
                label=f"laser {laser} peaks (extractor)")
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    ax.set_title(f"camera frame at encoder {frame.encoder_mm:.0f} mm (reference sensor)")
    ax.legend(loc="upper right")
    frame_png = os.path.join(out_dir, "frame.png")
    fig.savefig(frame_png, dpi=110)
    plt.close(fig)
    return frame_png


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="reconstruct_sheet_out", help="output directory for the PNGs")
    parser.add_argument("--seed", type=int, default=1, help="noise seed")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    print(f"flatline {flatline.__version__} (library {flatline.version()})")
    start = time.perf_counter()
    calib, rows, frame, peaks = simulate(args.seed)
    s, x, height, slope, z_true = rows.s, calib.fiber_x, rows.height, rows.slope, rows.truth
    print(f"sheet: {len(s)} rows x {len(x)} fibers, simulated in "
          f"{time.perf_counter() - start:.2f} s")

    start = time.perf_counter()
    z = flatline.reconstruct(s, height, slope, laser_spacing=calib.laser_spacing, rigid_motion=1)
    print(f"whole sheet reconstructed in {time.perf_counter() - start:.2f} s")
    start = time.perf_counter()
    sheets = on_the_line(calib, s, height, slope)
    z_line = np.concatenate([sheet.z for sheet in sheets])
    print(f"on the line (flatline.Gauge): {len(sheets)} sheets in "
          f"{time.perf_counter() - start:.2f} s")

    print(f"raw heights       vs true: {stats(height - z_true)}")
    print(f"whole sheet       vs true: {stats(z - z_true)}")
    print(f"gauge's sheets    vs true: {stats(z_line - z_true)}")
    for sheet in sheets:
        print(f"  sheet {sheet.id}: {sheet.s_start / 1000:.1f}-{sheet.s_end / 1000:.1f} m, "
              f"{sheet.shape} (confidence {sheet.confidence:.2f}), largest zone "
              f"{sheet.max_i_units:.1f} I-Units, largest wave {sheet.wave_height:.1f} mm "
              f"over {sheet.wave_period:.0f} mm")
    found = np.isfinite(peaks) & np.isfinite(frame.peak_rows)
    peak_rms = np.sqrt(np.mean((peaks[found] - frame.peak_rows[found]) ** 2))
    print(f"extractor peaks vs true line centres: RMS {peak_rms:.4f} px "
          f"in {100 * found.mean():.1f} % of the columns")

    fiber = int(np.argmin(np.abs(x - 0.0)))  # the centre: largest waves
    for path in (plot(args.out, s, x, height, z_line, z_true, fiber)
                 + (plot_zones(args.out, sheets), plot_frame(args.out, frame, peaks))):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
