#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Reruns the reference's three synthetic experiments and compares
libflatline's Hermite reconstructor against the reference's four classic
filters.

The sheet (the reference article, section 7.1; citation in README.md): 9000 mm along travel x 1500 mm
across, sampled every 3 mm of travel (3000 rows) and every 2 mm across (751
fibers), with centre buckles and wavy edges:
    z(s, x) = 12 sin(2 pi s / 1800) cos(2 pi x / 1500),   x in [-750, 750] mm
Two laser lines Delta-d = 100 mm apart; per row (frame at s) and fiber the
sensor gives
    height = (r_A + r_B) / 2,   slope = (r_B - r_A) / Delta-d
from laser A's reading r_A of the strip at s - Delta-d/2 and laser B's r_B
at s + Delta-d/2 (docs/sensor.md; the operators flt_reconstruct fits).

Experiments (the reference's):
  1. no noise;
  2. vibration N(0, 2.5 mm), roll eccentricity 0.5 mm sine of 50 mm period,
     peak-detection noise 1/16 px, taken here as 0.05 mm per laser reading
     (1/16 px at the reference camera's ~0.8 mm/px height resolution);
  3. experiment 2 plus shear transients: at every cut, cuts every 3000 mm
     (s = 0, 3000, 6000, 9000), a damped sine along travel
         w(u) = 50 exp(-0.07 u) sin(2 pi u / 10) mm,  u = s - cut >= 0 mm.
  Experiment 3 uses the very same noise draws as experiment 2 (same seed);
  experiment 1 has no noise and runs once.

Noise models (both reported):
  (a) literal: the noise is a field on the height image (3 mm x fiber grid,
      in material coordinates): vibration drawn per pixel (--literal-vibration
      row: one draw per image row), the eccentricity sine and the shear wave
      as functions of s, peak noise per pixel. Each laser reads the noisy
      image linearly interpolated at its position s -+ Delta-d/2, so the
      slope is the finite difference of the noisy heights Delta-d apart and
      the vibration does not cancel in it.
  (b) physical: the sheet shape is static. Per frame, a rigid heave N(0,
      2.5 mm) and the eccentricity (a sine of the encoder position) lift both
      lasers and every fiber equally, so they cancel in the slope. The shear
      wave travels on the strip: each laser sees it at its own material
      position. Peak noise is independent per laser, frame and fiber.

Methods:
  flt plain     flatline.reconstruct with the default options;
  flt weighted  height_sigma / slope_sigma set to the true noise levels of the
                experiment (the standard deviations of the simulated noise
                without the shear wave, measured on the realisation); not run
                on experiment 1, which has no noise to weight by;
  flt robust    robust="huber", rigid_motion=True, no noise level given: the
                method the targets apply to;
  flt huber     robust="huber" alone and flt tukey robust="tukey" with rigid_motion,
                for information;
  flt gauge     flt robust's options on the line: the rows pushed one by one
                into a flatline.Gauge (the streaming reconstructor running on
                across the cuts at 3000 and 6000 mm), the sheets' height maps
                put together: what an HMI gets;
  and the reference's baselines, applied along each fiber to the measured
  heights, zero phase:
  Moving average     filtfilt(ones(33)/33, 1);
  Chebyshev Type II  filtfilt of cheby2(3, 33 dB, Wn=0.02) (scipy's Wn:
                     fraction of the Nyquist frequency, as in the article);
  Savitzky-Golay     savgol_filter(order 3, frame 99): a symmetric FIR
                     smoother, already zero phase, so applied once;
  Butterworth        filtfilt of butter(3, Wn=0.01): the forward-backward
                     pass puts the -6 dB point at Wn, as the article states.
  filtfilt keeps scipy's default ends (odd extension, 3 x filter length, as
  MATLAB's filtfilt): the IIR filters' start-up transients at the sheet ends
  dominate their MaxAE, as they probably do in the article's Table 1.
  The baselines see the measured heights, the mean of the two lasers, which
  for the 1800 mm wave is 1.5% (up to 0.18 mm) below z(s): that is what the
  sensor gives them.

Metrics against the true surface z(s_row, x) at the row positions, over
every row and fiber: MAE = mean |e|, MaxAE = max |e|, STD = standard
deviation of |e| (the article's definition under its Table 1), RMSE. Each is
reported raw and after removing one constant for the whole sheet (the mean
error): the absolute level of a bouncing strip cannot be observed beyond
averaging, and flatness does not depend on it. With the mean removed, the
standard deviation of the signed error equals the RMSE column.

Targets (model (b), flt robust and flt gauge, constant removed, every
seed; the baseline factor for flt robust):
  experiment 3: MaxAE <= 0.30 mm and STD <= 0.06 mm, and every metric at
                least 3x better than the best baseline's;
  experiment 2: MaxAE <= 0.25 mm and STD <= 0.05 mm;
  experiment 1: MaxAE <= 1 um.
The program exits with status 1 if one fails, naming it.

Output (--out, default ./compare-report): results.csv (every experiment,
model, seed, method, raw and constant-removed metric, and the worst case
over seeds), results.json (the same, the configuration and the target
checks), and per experiment and model a PNG like the article's Figure 10
(raw heights, flt robust's reconstruction and its error as maps, the best
baseline's error map, and the centre fiber's profile with a close-up at the
cut at 3000 mm), from the first seed. Progress goes to stderr, the tables
to stdout.

Usage:
    python3 examples/python/compare_filters.py [--fibers N] [--seeds N]
                                               [--out DIR]
With the package built by CMake (not installed), point PYTHONPATH at it:
    PYTHONPATH=build/cmp/bindings/python/package \\
        /usr/bin/python3 examples/python/compare_filters.py
"""

import argparse
import csv
import json
import math
import os
import sys
import time

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy import signal  # noqa: E402

import flatline  # noqa: E402

# --- the reference's sheet and sensor -----------------------------------------
LENGTH = 9000.0  # mm along travel
STEP = 3.0  # mm of travel between frames (rows)
WIDTH = 1500.0  # mm across
FULL_FIBERS = 751  # 2 mm pitch across 1500 mm
AMPLITUDE = 12.0  # mm, both defects
PERIOD_ALONG = 1800.0  # mm
PERIOD_ACROSS = 1500.0  # mm
LASER_SPACING = 100.0  # mm, Delta-d

# --- the reference's noise -------------------------------------------------------
VIBRATION = 2.5  # mm, sigma
ECCENTRICITY = 0.5  # mm, amplitude of the roll's sine
ECCENTRICITY_PERIOD = 50.0  # mm of travel
PEAK_NOISE = 0.05  # mm per laser reading: 1/16 px at ~0.8 mm/px
SHEAR_ENVELOPE = 50.0  # mm, initial envelope of the damped sine
SHEAR_DECAY = 0.07  # 1/mm
SHEAR_PERIOD = 10.0  # mm
CUT_SPACING = 3000.0  # mm between cuts

EXPERIMENTS = {
    1: "no noise",
    2: "vibration + eccentricity + peak noise",
    3: "vibration + eccentricity + peak noise + shear transients",
}
MODELS = {"a": "literal (noise field on the height image)",
          "b": "physical (rigid heave per frame, shear wave on the strip)"}
METRICS = ("MAE", "MaxAE", "STD", "RMSE")

LIBRARY_METHODS = ("flt plain", "flt weighted", "flt robust", "flt huber", "flt tukey",
                   "flt gauge")
TARGET_METHOD = "flt robust"
GAUGE_METHOD = "flt gauge"  # the same options, streamed by the gauge
BASELINES = ("Butterworth", "Savitzky-Golay", "Moving average", "Chebyshev Type II")

# The article's numbers, mm (experiment 1 in mm too: 0.64 um, 0.16 um).
REFERENCE = {
    3: {"Hermite (reference)": (0.413, 1.15, 0.38, 0.459),
        "Butterworth": (0.760, 4.423, 0.735, 0.781),
        "Savitzky-Golay": (0.842, 6.436, 0.779, 0.853),
        "Moving average": (0.801, 5.463, 0.928, 0.865),
        "Chebyshev Type II": (0.828, 5.040, 0.828, 0.903)},
    2: {"Hermite (reference)": (None, 0.35, 0.12, None)},
    1: {"Hermite (reference)": (None, 0.64e-3, 0.16e-3, None)},
}
# Which of our rows the reference's Hermite row sits beside.
REFERENCE_ROW = {"flt plain": "Hermite (reference)"}

# Targets on model (b), flt robust, constant removed: (metric, bound in mm).
TARGETS = {3: (("MaxAE", 0.30), ("STD", 0.06)),
           2: (("MaxAE", 0.25), ("STD", 0.05)),
           1: (("MaxAE", 1e-3),)}
BASELINE_FACTOR = 3.0  # experiment 3: every metric this much better


def progress(message):
    print(message, file=sys.stderr, flush=True)


# --- the sheet ------------------------------------------------------------------

def true_surface(s, x):
    """z (len(s), len(x)) in mm: centre buckle and wavy edges."""
    return AMPLITUDE * np.outer(np.sin(2 * np.pi * s / PERIOD_ALONG),
                                np.cos(2 * np.pi * x / PERIOD_ACROSS))


def shear_wave(s):
    """The shear station's ringing at material positions s (mm): a damped
    sine starting at every cut, cuts every CUT_SPACING from s = 0."""
    wave = np.zeros_like(s)
    first = math.floor(s.min() / CUT_SPACING)
    last = math.floor(s.max() / CUT_SPACING)
    for k in range(first, last + 1):
        u = s - k * CUT_SPACING
        after = u >= 0
        wave[after] += (SHEAR_ENVELOPE * np.exp(-SHEAR_DECAY * u[after])
                        * np.sin(2 * np.pi * u[after] / SHEAR_PERIOD))
    return wave


class Measurement:
    """What the sensor gives for one experiment: heights and slopes (rows x
    fibers), and the standard deviations of their noise (shear excluded)."""

    def __init__(self, height, slope, height_sigma, slope_sigma):
        self.height = height
        self.slope = slope
        self.height_sigma = height_sigma
        self.slope_sigma = slope_sigma


def combine(reading_a, reading_b):
    return 0.5 * (reading_a + reading_b), (reading_b - reading_a) / LASER_SPACING


def simulate_physical(s, x, seed):
    """Model (b): experiments 1-3 from one seed's draws. Returns {exp:
    Measurement}."""
    rng = np.random.default_rng([seed, 0xB])
    rows, fibers = len(s), len(x)
    s_a, s_b = s - LASER_SPACING / 2, s + LASER_SPACING / 2
    clean_a, clean_b = true_surface(s_a, x), true_surface(s_b, x)
    # Per frame: the rigid heave and the roll's eccentricity (a sine of the
    # encoder position, which is the frame's s) hit both lasers and every
    # fiber alike.
    phase = rng.uniform(0, 2 * np.pi)
    frame_offset = (rng.normal(0.0, VIBRATION, rows)
                    + ECCENTRICITY * np.sin(2 * np.pi * s / ECCENTRICITY_PERIOD + phase))
    noise_a = frame_offset[:, None] + rng.normal(0.0, PEAK_NOISE, (rows, fibers))
    noise_b = frame_offset[:, None] + rng.normal(0.0, PEAK_NOISE, (rows, fibers))
    # The shear wave is on the strip: each laser sees it where it looks.
    shear_a, shear_b = shear_wave(s_a)[:, None], shear_wave(s_b)[:, None]
    return measurements(clean_a, clean_b, noise_a, noise_b, shear_a, shear_b)


def simulate_literal(s, x, seed, vibration_per="pixel"):
    """Model (a): a noise field on the height image (material coordinates,
    STEP x fiber grid), read by each laser at s -+ Delta-d/2 with linear
    interpolation along travel."""
    rng = np.random.default_rng([seed, 0xA])
    fibers = len(x)
    margin = LASER_SPACING / 2 + 2 * STEP
    image_s = np.arange(math.floor((s[0] - margin) / STEP),
                        math.ceil((s[-1] + margin) / STEP) + 1) * STEP
    image_rows = len(image_s)
    if vibration_per == "pixel":
        vibration = rng.normal(0.0, VIBRATION, (image_rows, fibers))
    else:
        vibration = rng.normal(0.0, VIBRATION, image_rows)[:, None]
    phase = rng.uniform(0, 2 * np.pi)
    noise = (vibration
             + ECCENTRICITY * np.sin(2 * np.pi * image_s / ECCENTRICITY_PERIOD + phase)[:, None]
             + rng.normal(0.0, PEAK_NOISE, (image_rows, fibers)))
    clean = true_surface(image_s, x)
    shear = shear_wave(image_s)[:, None]

    def read(field, at):
        position = (at - image_s[0]) / STEP
        index = np.floor(position).astype(int)
        frac = (position - index)[:, None]
        return (1 - frac) * field[index] + frac * field[index + 1]

    s_a, s_b = s - LASER_SPACING / 2, s + LASER_SPACING / 2
    return measurements(read(clean, s_a), read(clean, s_b),
                        read(noise, s_a), read(noise, s_b),
                        read(shear, s_a), read(shear, s_b))


def measurements(clean_a, clean_b, noise_a, noise_b, shear_a, shear_b):
    height_clean, slope_clean = combine(clean_a, clean_b)
    height_noise, slope_noise = combine(noise_a, noise_b)
    height_shear, slope_shear = combine(shear_a, shear_b)
    # The true noise levels, for the noise-weighted method: what the noise
    # of this realisation really is (the shear wave is not noise of a known
    # level but a transient, which is what the robust mode is for).
    height_sigma, slope_sigma = float(height_noise.std()), float(slope_noise.std())
    return {
        1: Measurement(height_clean, slope_clean, 0.0, 0.0),
        2: Measurement(height_clean + height_noise, slope_clean + slope_noise,
                       height_sigma, slope_sigma),
        3: Measurement(height_clean + height_noise + height_shear,
                       slope_clean + slope_noise + slope_shear,
                       height_sigma, slope_sigma),
    }


# --- the methods ----------------------------------------------------------------

def library_options(method, measurement):
    if method == "flt plain":
        return {}
    if method == "flt weighted":
        if measurement.height_sigma == 0.0:
            return None  # experiment 1: no noise to weight by
        return {"height_sigma": measurement.height_sigma,
                "slope_sigma": measurement.slope_sigma}
    if method == "flt robust":
        return {"robust": "huber", "rigid_motion": True}
    if method == "flt huber":
        return {"robust": "huber"}
    if method == "flt tukey":
        return {"robust": "tukey", "rigid_motion": True}
    if method == "flt gauge":
        return {"robust": "huber", "rigid_motion": True}
    raise KeyError(method)


def gauge_reconstruct(s, x, measurement, options):
    """The rows through a flatline.Gauge, as on the line: pushed one by one
    at their encoder positions, the shear's cuts given, the sheets' height
    maps put together. The sensor is the reference one with this fiber
    grid (laser spacing 100 mm, as LASER_SPACING)."""
    calib = flatline.Calibration.reference(first_row=892, rows=256, first_x_mm=float(x[0]),
                                           pitch_mm=float(x[1] - x[0]), fibers=len(x))
    centre = sum(calib.laser_offsets) / 2  # a row at s: the frame at encoder s + centre
    with flatline.Gauge(calib, gauge_frame_spacing=0.8 * STEP, gauge_overflow=1,
                        gauge_keep_maps=1, gauge_sheet_slots=8, **options) as gauge:
        for cut in np.arange(CUT_SPACING, s[-1], CUT_SPACING):
            gauge.cut(cut + centre)
        for r in range(len(s)):
            gauge.push_row(s[r] + centre, measurement.height[r], measurement.slope[r])
        gauge.flush()
        sheets = list(gauge)
    assert np.array_equal(np.concatenate([sheet.s for sheet in sheets]), s)
    return np.concatenate([sheet.z for sheet in sheets])


def baseline(method, height):
    """The reference's filters along each fiber (axis 0, travel)."""
    if method == "Moving average":
        return signal.filtfilt(np.ones(33) / 33, [1.0], height, axis=0)
    if method == "Chebyshev Type II":
        b, a = signal.cheby2(3, 33, 0.02)
        return signal.filtfilt(b, a, height, axis=0)
    if method == "Savitzky-Golay":
        return signal.savgol_filter(height, 99, 3, axis=0)
    if method == "Butterworth":
        b, a = signal.butter(3, 0.01)
        return signal.filtfilt(b, a, height, axis=0)
    raise KeyError(method)


def metrics(error):
    """(MAE, MaxAE, STD of |e|, RMSE), mm."""
    absolute = np.abs(error)
    return (float(absolute.mean()), float(absolute.max()), float(absolute.std()),
            float(np.sqrt(np.mean(error ** 2))))


# --- one run --------------------------------------------------------------------

def run_case(s, x, z_true, measurement, methods, keep=None):
    """{method: {"raw": metrics, "const": metrics, "ms": time}} and, for the
    methods in keep, their reconstructions."""
    results, kept = {}, {}
    for method in methods:
        start = time.perf_counter()
        if method in BASELINES:
            z = baseline(method, measurement.height)
        else:
            options = library_options(method, measurement)
            if options is None:
                continue
            if method == "flt gauge":
                z = gauge_reconstruct(s, x, measurement, options)
            else:
                z = flatline.reconstruct(s, measurement.height, measurement.slope, **options)
        elapsed_ms = 1e3 * (time.perf_counter() - start)
        error = z - z_true
        results[method] = {"raw": metrics(error),
                           "const": metrics(error - error.mean()),
                           "ms": elapsed_ms}
        if keep and method in keep:
            kept[method] = z
    return results, kept


# --- report ---------------------------------------------------------------------

def unit_of(experiment):
    return (1e3, "um") if experiment == 1 else (1.0, "mm")


def format_values(values, scale, width=7):
    cells = []
    for v in values:
        if v is None:
            cells.append(" " * width)
        else:
            digits = 3 if scale * v < 100 else 1
            cells.append(f"{scale * v:{width}.{digits}f}")
    return " ".join(cells)


def worst(per_seed, method, kind):
    """Per metric, the worst value over the seeds (each metric on its own)."""
    rows = [results[method][kind] for results in per_seed if method in results]
    return tuple(max(r[i] for r in rows) for i in range(len(METRICS))) if rows else None


def print_table(experiment, model, per_seed, methods):
    scale, unit = unit_of(experiment)
    seeds = [results["_seed"] for results in per_seed]
    if experiment == 1:
        label = "no noise, the same for every seed"
    elif len(seeds) > 1:
        label = "worst of %d seeds" % len(seeds)
    else:
        label = "seed %d" % seeds[0]
    print()
    print(f"Experiment {experiment} ({EXPERIMENTS[experiment]}), model ({model}) "
          f"{MODELS[model]}: {label}, {unit}")
    head = " ".join(f"{m:>7}" for m in METRICS)
    print(f"{'Method':<20} | {'raw':^31} | {'one constant removed':^31} | "
          f"{'reference Table 1' if experiment == 3 else 'reference':^31} | {'ms':>6}")
    print(f"{'':<20} | {head} | {head} | {head} |")
    reference = REFERENCE[experiment]
    for method in methods:
        raw, const = worst(per_seed, method, "raw"), worst(per_seed, method, "const")
        if raw is None:
            print(f"{method:<20} | {'(no noise to weight by)':<31} |")
            continue
        ref_name = REFERENCE_ROW.get(method, method)
        ref = reference.get(ref_name)
        ref_cells = format_values(ref, scale) if ref else " " * 31
        ms = np.mean([results[method]["ms"] for results in per_seed])
        print(f"{method:<20} | {format_values(raw, scale)} | {format_values(const, scale)} | "
              f"{ref_cells} | {ms:6.0f}")
    if len(seeds) > 1:
        print(f"  per seed, constant removed ({unit}):")
        for method in (TARGET_METHOD, best_baseline_name(per_seed)):
            for results in per_seed:
                values = format_values(results[method]["const"], scale)
                print(f"    {method:<18} seed {results['_seed']}: {values}")


def best_baseline_name(per_seed):
    """The baseline with the lowest worst-case RMSE (constant removed)."""
    return min(BASELINES, key=lambda m: worst(per_seed, m, "const")[3])


def check_targets(table):
    """[(passed, text)] for every target."""
    checks = []
    # The targets hold for the reconstructor on a whole sheet and for what
    # the gauge streams on the line with the same options.
    for method in (TARGET_METHOD, GAUGE_METHOD):
        for experiment, bounds in TARGETS.items():
            per_seed = table[(experiment, "b")]
            for metric, bound in bounds:
                i = METRICS.index(metric)
                values = [results[method]["const"][i] for results in per_seed]
                scale, unit = unit_of(experiment)
                ok = max(values) <= bound
                checks.append((ok, f"experiment {experiment}, model (b), {method}, "
                                   f"constant removed: {metric} worst "
                                   f"{scale * max(values):.4f} {unit} (target <= "
                                   f"{scale * bound:g} {unit})"))
    per_seed = table[(3, "b")]
    for i, metric in enumerate(METRICS):
        ratios = []
        for results in per_seed:
            best = min(results[m]["const"][i] for m in BASELINES)
            ratios.append(best / results[TARGET_METHOD]["const"][i])
        ok = min(ratios) >= BASELINE_FACTOR
        checks.append((ok, f"experiment 3, model (b): {metric} of the best baseline / "
                           f"{TARGET_METHOD}, smallest over seeds {min(ratios):.1f}x "
                           f"(target >= {BASELINE_FACTOR:g}x)"))
    return checks


# --- figures --------------------------------------------------------------------

def figure(path, experiment, model, s, x, measurement, z_true, z, z_baseline,
           baseline_name, fiber):
    """Like the article's Figure 10: raw heights, reconstruction and error as
    images (height relative to the sheet's mean, white = up), plus one fiber's
    profile and a close-up at a cut."""
    error = z - z_true
    error = error - error.mean()
    raw = measurement.height
    fig = plt.figure(figsize=(15, 11), constrained_layout=True)
    top, bottom = fig.subfigures(2, 1, height_ratios=[1.35, 1])
    map_axes = top.subplots(1, 4)
    profile_axes = bottom.subplots(1, 2, width_ratios=[3, 1])
    extent = [x[0], x[-1], s[-1] / 1000, s[0] / 1000]  # width mm, travel m
    limit = AMPLITUDE * 1.25
    panels = [(raw - raw.mean(), "(a) raw heights (mean of the lasers)", "gray", limit, "z [mm]"),
              (z - z.mean(), f"(b) reconstructed, {TARGET_METHOD}", "gray", limit, "z [mm]")]
    error_limit = max(np.abs(error).max(), 1e-12)
    scale, unit = unit_of(experiment)
    panels.append((scale * error, "(c) reconstructed - true\n(one constant removed)",
                   "RdBu_r", scale * error_limit, f"error [{unit}]"))
    baseline_error = z_baseline - z_true
    baseline_error -= baseline_error.mean()
    b_limit = max(np.abs(baseline_error).max(), 1e-12)
    panels.append((scale * baseline_error, f"(d) {baseline_name} - true\n(one constant removed)",
                   "RdBu_r", scale * b_limit, f"error [{unit}]"))
    for column, (image, title, cmap, vlim, label) in enumerate(panels):
        ax = map_axes[column]
        im = ax.imshow(image, aspect="auto", extent=extent, cmap=cmap, vmin=-vlim,
                       vmax=vlim, interpolation="nearest")
        ax.set_title(title, fontsize=11)
        ax.set_xlabel("x across the width [mm]")
        if column == 0:
            ax.set_ylabel("s along travel [m]")
        ax.axvline(x[fiber], color="tab:orange", lw=0.8, ls=":")
        top.colorbar(im, ax=ax, label=label,
                     extend="both" if column < 2 else "neither")

    ax = profile_axes[0]
    column = raw[:, fiber]
    ax.plot(s / 1000, column, lw=0.5, color="0.6", label="raw height")
    ax.plot(s / 1000, z_baseline[:, fiber], lw=1.0, color="tab:blue", label=baseline_name)
    ax.plot(s / 1000, z_true[:, fiber], lw=2.5, color="tab:green", label="true")
    ax.plot(s / 1000, z[:, fiber], lw=1.0, color="tab:red", ls="--", label=TARGET_METHOD)
    ax.set_ylim(-AMPLITUDE * 1.6, AMPLITUDE * 1.6)
    ax.set_xlabel("s along travel [m]")
    ax.set_ylabel("z [mm]")
    ax.set_title(f"fiber at x = {x[fiber]:.0f} mm (raw clipped to the axis)", fontsize=11)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", ncol=4, fontsize=9)
    ax_err = ax.twinx()
    ax_err.plot(s / 1000, scale * (error[:, fiber]), lw=0.8, color="tab:purple")
    ax_err.set_ylabel(f"{TARGET_METHOD} error [{unit}]", color="tab:purple")
    ax_err.tick_params(axis="y", colors="tab:purple")
    e_lim = 1.5 * scale * error_limit
    ax_err.set_ylim(-e_lim, e_lim)

    # Close-up around the cut at 3000 mm (where experiment 3's ringing is).
    ax = profile_axes[1]
    near = (s > CUT_SPACING - 300) & (s < CUT_SPACING + 500)
    ax.plot(s[near], column[near], lw=0.6, color="0.6", marker=".", ms=2, label="raw")
    ax.plot(s[near], z_baseline[near, fiber], lw=1.0, color="tab:blue", label=baseline_name)
    ax.plot(s[near], z_true[near, fiber], lw=2.5, color="tab:green", label="true")
    ax.plot(s[near], z[near, fiber], lw=1.0, color="tab:red", ls="--", label=TARGET_METHOD)
    truth = z_true[near, fiber]
    pad = max(3.0, np.ptp(truth))
    ax.set_ylim(truth.min() - pad, truth.max() + pad)
    ax.set_xlabel("s along travel [mm]")
    ax.set_title(f"close-up at the cut s = {CUT_SPACING:.0f} mm", fontsize=11)
    ax.grid(alpha=0.3)
    ax_err = ax.twinx()
    ax_err.plot(s[near], scale * error[near, fiber], lw=0.8, color="tab:purple")
    ax_err.set_ylim(-e_lim, e_lim)
    ax_err.tick_params(axis="y", colors="tab:purple")

    fig.suptitle(f"Experiment {experiment}: {EXPERIMENTS[experiment]} - model ({model}) "
                 f"{MODELS[model]}", fontsize=13)
    fig.savefig(path, dpi=90)
    plt.close(fig)


# --- main -------------------------------------------------------------------------

def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fibers", type=int, default=FULL_FIBERS,
                        help="fibers across the 1500 mm width (default %(default)s: "
                             "2 mm pitch); fewer runs faster")
    parser.add_argument("--seeds", type=int, default=5,
                        help="noise seeds 1..N (default %(default)s); the targets "
                             "must hold for each")
    parser.add_argument("--out", default="compare-report",
                        help="output directory (default %(default)s)")
    parser.add_argument("--literal-vibration", choices=("pixel", "row"), default="pixel",
                        help="model (a): draw the vibration per pixel of the height "
                             "image (default) or once per image row")
    parser.add_argument("--no-figures", action="store_true", help="skip the PNGs")
    args = parser.parse_args(argv)
    if args.fibers < 3 or args.seeds < 1:
        parser.error("--fibers must be >= 3 and --seeds >= 1")
    os.makedirs(args.out, exist_ok=True)

    s = np.arange(int(round(LENGTH / STEP))) * STEP  # rows at 0, 3, ..., 8997 mm
    x = np.linspace(-WIDTH / 2, WIDTH / 2, args.fibers)
    z_true = true_surface(s, x)
    seeds = list(range(1, args.seeds + 1))
    methods = LIBRARY_METHODS + BASELINES
    progress(f"compare_filters: {len(s)} rows x {len(x)} fibers "
             f"(pitch {x[1] - x[0]:.3g} mm), seeds {seeds}, flatline {flatline.version()}")

    table = {}  # (experiment, model) -> [results per seed]
    figures = []
    # The fiber of the profile plots: the centre, where the centre buckle
    # has its full 12 mm (a quarter of the width in, cos(2 pi x / 1500) is
    # almost 0 and the profile would show nothing).
    fiber = (len(x) - 1) // 2
    started = time.perf_counter()
    for seed in seeds:
        for model in ("a", "b"):
            if model == "a":
                sheets = simulate_literal(s, x, seed, args.literal_vibration)
            else:
                sheets = simulate_physical(s, x, seed)
            for experiment in (1, 2, 3):
                if experiment == 1 and seed != seeds[0]:
                    continue  # no noise: every seed gives the same sheet
                t0 = time.perf_counter()
                keep = None
                if seed == seeds[0] and not args.no_figures:
                    keep = (TARGET_METHOD,) + BASELINES
                results, kept = run_case(s, x, z_true, sheets[experiment], methods, keep)
                results["_seed"] = seed
                table.setdefault((experiment, model), []).append(results)
                if kept:
                    # Drawn now, so the reconstructions need not be kept: the
                    # baseline shown is this seed's best (constant-removed RMSE).
                    name = min(BASELINES, key=lambda m: results[m]["const"][3])
                    path = os.path.join(args.out, f"figure10_exp{experiment}_model_{model}.png")
                    figure(path, experiment, model, s, x, sheets[experiment], z_true,
                           kept[TARGET_METHOD], kept[name], name, fiber)
                    figures.append(path)
                    del kept
                progress(f"  seed {seed} model ({model}) experiment {experiment}: "
                         f"{time.perf_counter() - t0:.1f} s; {TARGET_METHOD} MaxAE "
                         f"{results[TARGET_METHOD]['const'][1]:.4f} mm, STD "
                         f"{results[TARGET_METHOD]['const'][2]:.4f} mm (constant removed)")
            del sheets
    elapsed = time.perf_counter() - started

    print(f"libflatline {flatline.version()} vs the reference's filters: "
          f"{len(s)} rows x {len(x)} fibers ({STEP:g} mm x {x[1] - x[0]:.3g} mm), "
          f"Delta-d {LASER_SPACING:g} mm, peak noise {PEAK_NOISE} mm per laser, "
          f"seeds {seeds[0]}..{seeds[-1]}")
    print("STD = standard deviation of |error| (the article's); worst case = per metric, "
          "the largest over the seeds; ms = mean time per call.")
    for experiment in (1, 2, 3):
        for model in ("b", "a"):
            print_table(experiment, model, table[(experiment, model)], methods)

    checks = check_targets(table)
    print()
    print("Targets (model (b), flt robust = robust=huber rigid_motion, no noise level given, "
          "constant removed, every seed):")
    for ok, text in checks:
        print(f"  {'PASS' if ok else 'FAIL'}  {text}")
    print(f"({elapsed:.1f} s)")

    write_outputs(args, table, seeds, methods, checks, len(x))
    for path in figures:
        progress(f"  wrote {path}")

    failed = [text for ok, text in checks if not ok]
    if failed:
        print("FAILED targets:", file=sys.stderr)
        for text in failed:
            print("  " + text, file=sys.stderr)
        return 1
    return 0


def write_outputs(args, table, seeds, methods, checks, fibers):
    rows = []
    for (experiment, model), per_seed in sorted(table.items()):
        for method in methods:
            for results in per_seed:
                if method in results:
                    for kind in ("raw", "const"):
                        rows.append([experiment, model, results["_seed"], method, kind,
                                     *results[method][kind], results[method]["ms"]])
            for kind in ("raw", "const"):
                values = worst(per_seed, method, kind)
                if values:
                    rows.append([experiment, model, "worst", method, kind, *values, ""])
    csv_path = os.path.join(args.out, "results.csv")
    with open(csv_path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["experiment", "model", "seed", "method", "errors",
                      "MAE_mm", "MaxAE_mm", "STD_abs_mm", "RMSE_mm", "ms"])
        out.writerows(rows)
    json_path = os.path.join(args.out, "results.json")
    with open(json_path, "w") as f:
        json.dump({
            "config": {"length_mm": LENGTH, "step_mm": STEP, "width_mm": WIDTH,
                       "fibers": fibers, "laser_spacing_mm": LASER_SPACING,
                       "vibration_mm": VIBRATION, "eccentricity_mm": ECCENTRICITY,
                       "eccentricity_period_mm": ECCENTRICITY_PERIOD,
                       "peak_noise_mm": PEAK_NOISE, "shear_envelope_mm": SHEAR_ENVELOPE,
                       "shear_decay_per_mm": SHEAR_DECAY, "shear_period_mm": SHEAR_PERIOD,
                       "cut_spacing_mm": CUT_SPACING, "seeds": seeds,
                       "literal_vibration": args.literal_vibration,
                       "flatline_version": flatline.version()},
            "errors": {"raw": "z - z_true", "const": "z - z_true - mean(z - z_true)",
                       "STD": "standard deviation of |error|"},
            "results": [dict(zip(["experiment", "model", "seed", "method", "errors",
                                  "MAE_mm", "MaxAE_mm", "STD_abs_mm", "RMSE_mm", "ms"], r))
                        for r in rows],
            "targets": [{"passed": ok, "check": text} for ok, text in checks],
        }, f, indent=1)
    progress(f"  wrote {csv_path} and {json_path}")


if __name__ == "__main__":
    sys.exit(main())
