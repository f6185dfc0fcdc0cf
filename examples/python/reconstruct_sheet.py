#!/usr/bin/env python3
"""Simulates the reference sheet, reconstructs it with libflatline, and plots
raw against reconstructed heights to PNG files.

The sheet (DESIGN.md, after the seed article): centre buckles and wavy edges,
    z(s, x) = 12 sin(2 pi s / 1800) cos(2 pi x / 1500)   [mm]
9000 mm long, measured every 3 mm of travel, fibers every 10 mm across
1500 mm. Two laser lines 100 mm apart each see the surface at s -+ 50 mm:
    height = (z(s - 50) + z(s + 50)) / 2,   slope = (z(s + 50) - z(s - 50)) / 100
with the strip bouncing by N(0, 2.5 mm) per frame (both lasers, every fiber:
it leaves the slope untouched) and N(0, 0.05 mm) of peak-detection noise per
laser and fiber.

It reconstructs twice: the whole sheet at once (flatline.reconstruct) and
streaming, frame block by frame block, as the gauge runs on the line
(flatline.Reconstructor), and prints the accuracy of both against the truth.

The I-Unit profile across the width comes with the flatness component of
libflatline (flatline.i_units); this example will plot it once the binding
has it.

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
LASER_SPACING = 100.0  # mm between the two laser lines
VIBRATION = 2.5  # mm, sigma of the strip's bounce per frame
PEAK_NOISE = 0.05  # mm, sigma of one laser's height per fiber


def surface(s, x):
    """The true sheet, z (mm) at travel s (mm, column) and width x (mm, row)."""
    return 12.0 * np.sin(2 * np.pi * s[:, None] / 1800.0) * np.cos(2 * np.pi * x[None, :] / 1500.0)


def simulate(rng):
    s = np.arange(0.0, LENGTH, STEP)
    x = np.arange(0.0, WIDTH + PITCH / 2, PITCH)
    rows, fibers = len(s), len(x)
    bounce = rng.normal(0.0, VIBRATION, (rows, 1))  # one per frame, all fibers
    behind = surface(s - LASER_SPACING / 2, x) + bounce + rng.normal(0, PEAK_NOISE, (rows, fibers))
    ahead = surface(s + LASER_SPACING / 2, x) + bounce + rng.normal(0, PEAK_NOISE, (rows, fibers))
    height = (behind + ahead) / 2
    slope = (ahead - behind) / LASER_SPACING
    return s, x, height, slope, surface(s, x)


def stream(s, height, slope, block=100):
    """The on-line way: frames arrive in blocks, finished rows come out later."""
    parts = []
    with flatline.Reconstructor(height.shape[1], laser_spacing=LASER_SPACING) as recon:
        for start in range(0, len(s), block):
            rows = slice(start, start + block)
            recon.push(s[rows], height[rows], slope[rows])
            parts.append(recon.pull())
        recon.end_sheet()
        parts.append(recon.pull())
    out_s, z, flags = (np.concatenate(p) for p in zip(*parts))
    assert np.array_equal(out_s, s) and not flags.any()
    return z


def stats(error):
    return (f"max {np.abs(error).max():.3f} mm, RMSE {np.sqrt(np.mean(error ** 2)):.3f} mm, "
            f"std {error.std():.3f} mm")


def plot(out_dir, s, x, height, z, z_true, fiber):
    extent = [x[0], x[-1], s[-1] / 1000, s[0] / 1000]  # width mm, travel m
    limit = max(np.abs(height).max(), np.abs(z).max())
    fig, axes = plt.subplots(1, 3, figsize=(13, 6), sharey=True, constrained_layout=True)
    error = z - z_true
    panels = [(height, "raw heights (mean of the lasers)", limit, "z [mm]"),
              (z, "reconstructed", limit, "z [mm]"),
              (error, "reconstructed - true", np.abs(error).max(), "error [mm]")]
    for ax, (image, title, scale, label) in zip(axes, panels):
        im = ax.imshow(image, aspect="auto", extent=extent, cmap="RdBu_r",
                       vmin=-scale, vmax=scale, interpolation="nearest")
        ax.set_title(title)
        ax.set_xlabel("x across the width [mm]")
        fig.colorbar(im, ax=ax, shrink=0.8, label=label)
    axes[0].set_ylabel("s along travel [m]")
    fig.suptitle(f"Reference sheet {LENGTH / 1000:.0f} m x {WIDTH:.0f} mm, "
                 f"vibration {VIBRATION} mm, peak noise {PEAK_NOISE} mm")
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="reconstruct_sheet_out", help="output directory for the PNGs")
    parser.add_argument("--seed", type=int, default=1, help="noise seed")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    print(f"flatline {flatline.__version__} (library {flatline.version()})")
    s, x, height, slope, z_true = simulate(np.random.default_rng(args.seed))
    print(f"sheet: {len(s)} rows x {len(x)} fibers")

    start = time.perf_counter()
    z = flatline.reconstruct(s, height, slope, laser_spacing=LASER_SPACING)
    print(f"whole sheet reconstructed in {time.perf_counter() - start:.2f} s")
    start = time.perf_counter()
    z_stream = stream(s, height, slope)
    print(f"streamed in {time.perf_counter() - start:.2f} s")

    print(f"raw heights   vs true: {stats(height - z_true)}")
    print(f"reconstructed vs true: {stats(z - z_true)}")
    print(f"streamed      vs true: {stats(z_stream - z_true)}")

    fiber = int(np.argmin(np.abs(x - 0.0)))  # the edge: largest waves
    for path in plot(args.out, s, x, height, z, z_true, fiber):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
