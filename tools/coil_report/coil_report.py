#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The coil report: one self-contained HTML page per coil, from the gauge's
sheets, with PNG figures beside it.

For every coil it writes ``<out>/coil_<id>/index.html`` and, beside it:

- ``coil_heights.png``: the height map of the whole coil, sheet after sheet
  (s along travel, x across, the drive and operator sides labelled);
- ``sheet_<id>_heights.png``: each sheet's height map, with the places where
  the rules found their worst values marked;
- ``zone_profiles.png``: the zone profile (I-Units per zone, drive side to
  operator side) of every sheet, one line per sheet;
- ``rule_histograms.png``: per rule, the distribution of the sheets' worst
  values against the limit;
- ``verdicts.csv``: the verdict table at full precision.

The page holds the per-coil summary (sheets, pass and fail counts per rule),
the verdict table (per sheet and rule: limit, worst value, its position,
margin, pass or fail) and the advisor's suggestions. ``<out>/index.html``
lists the coils. The verdicts come from ``flatline.Verdict`` over a rule
file (``example_rules.json`` beside this file holds invented example
limits, not a standard's).

The sheets come from the built-in simulator (a simulated line with a few
coils and defects, measured by a ``flatline.Gauge``) or from the caller's
own gauge (``write_reports``). Usage:

    PYTHONPATH=build/dev/bindings/python/package /usr/bin/python3 \\
        tools/coil_report/coil_report.py --out coil-report

README.md beside this file has the options, the Python API and the shape
of the advisor's suggestions.
"""

from __future__ import annotations

import argparse
import csv
import html
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from typing import (Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple,
                    Union)

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap, TwoSlopeNorm  # noqa: E402

import flatline  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLE_RULES = os.path.join(HERE, "example_rules.json")

Progress = Callable[[str], None]

#: The unit each measure's values are in (the rule file's limits too).
UNITS = {
    flatline.Measure.STRAIGHTEDGE_ALONG: "mm",
    flatline.Measure.STRAIGHTEDGE_ACROSS: "mm",
    flatline.Measure.ZONE_I_UNITS: "I-Units",
    flatline.Measure.WAVE_STEEPNESS: "%",
    flatline.Measure.WAVE_HEIGHT: "mm",
    flatline.Measure.BOW: "mm",
    flatline.Measure.CROSSBOW: "mm",
}

#: What each measure is, in words.
MEASURE_TEXT = {
    flatline.Measure.STRAIGHTEDGE_ALONG: "straightedge along the strip",
    flatline.Measure.STRAIGHTEDGE_ACROSS: "straightedge across the strip",
    flatline.Measure.ZONE_I_UNITS: "largest zone I-Units",
    flatline.Measure.WAVE_STEEPNESS: "steepness of the largest wave",
    flatline.Measure.WAVE_HEIGHT: "largest wave, peak to peak",
    flatline.Measure.BOW: "bow (coil set) sagitta",
    flatline.Measure.CROSSBOW: "crossbow sagitta",
}

#: Decimals shown for each unit (the CSV and the page's data-value keep all).
DECIMALS = {"mm": 2, "I-Units": 1, "%": 2}

#: Measures found at a point of the height map (x and s); the others are
#: whole-sheet measures: their x is where the library puts them (the
#: largest zone's centre, the largest wave's fiber) and s the sheet's middle.
LOCAL = (flatline.Measure.STRAIGHTEDGE_ALONG, flatline.Measure.STRAIGHTEDGE_ACROSS)

STATE_TEXT = {
    flatline.VerdictState.PASS: "pass",
    flatline.VerdictState.FAIL: "FAIL",
    flatline.VerdictState.NO_BAND: "no band",
    flatline.VerdictState.NOT_MEASURED: "not measured",
    flatline.VerdictState.NOT_JUDGED: "not judged: incomplete",
}


def sheet_state(sheet: flatline.Sheet,
                row: Sequence[flatline.RuleResult]) -> flatline.VerdictState:
    """A sheet's verdict over its rules: FAIL when a rule failed, PASS only
    when every rule judged it and passed; else NOT_JUDGED (a rule with no
    band or a missing measure, or an incomplete sheet): never a pass."""
    if sheet.incomplete:
        return flatline.VerdictState.NOT_JUDGED
    if any(r.state == flatline.VerdictState.FAIL for r in row):
        return flatline.VerdictState.FAIL
    if row and all(r.state == flatline.VerdictState.PASS for r in row):
        return flatline.VerdictState.PASS
    return flatline.VerdictState.NOT_JUDGED


# ---------------------------------------------------------------------------
# The simulated line
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class SimCoil:
    """One simulated coil: its thickness (chooses the rule bands), the
    number of sheets the shear cuts it into, and its defects, each
    (kind, amplitude mm, period mm) as ``flatline.SimulatedLine.add_defect``
    takes them (kind: "centre_buckle", "wavy_edge_left" (the drive side),
    "wavy_edge_right", "wavy_edge_both", "quarter_buckle", "bow",
    "crossbow"). Two defects of the same kind with nearby periods beat:
    the amplitude then changes from sheet to sheet, as on a real coil."""

    thickness_mm: float
    sheets: int
    defects: Tuple[Tuple[str, float, float], ...]


#: The default line: three coils of four sheets, a mild centre buckle, a
#: long drive-side edge, long quarters with coil set and crossbow.
DEFAULT_COILS = (
    SimCoil(3.0, 4, (("centre_buckle", 1.6, 1800.0), ("centre_buckle", 0.9, 2300.0))),
    SimCoil(5.0, 4, (("wavy_edge_left", 4.0, 1200.0), ("wavy_edge_left", 2.0, 1450.0),
                     ("centre_buckle", 0.5, 1800.0))),
    SimCoil(8.0, 4, (("quarter_buckle", 1.2, 1600.0), ("quarter_buckle", 0.6, 1900.0),
                     ("bow", 6.0, 9000.0), ("crossbow", 1.2, 0.0))),
)


@dataclass
class LineRun:
    """What a run of the simulated line gives the report."""

    sheets: List[flatline.Sheet]
    fiber_x: np.ndarray  #: (K,) the height map's columns, sensor x, mm
    thickness_mm: Dict[int, float]  #: per coil id
    drive_side_high_x: bool  #: the gauge's flat_drive_side


def simulate_line(coils: Sequence[SimCoil] = DEFAULT_COILS, sheet_length_mm: float = 3000.0,
                  width_mm: float = 1500.0, pitch_mm: float = 10.0, step_mm: float = 3.0,
                  vibration_mm: float = 1.0, peak_noise_px: float = 1 / 16, seed: int = 1,
                  progress: Optional[Progress] = print) -> LineRun:
    """Runs the simulated line: per coil a SimulatedLine with its defects
    (profile rows every step_mm, the strip bouncing by N(0, vibration_mm)
    per frame and peak_noise_px of peak-detection noise), pushed into one
    flatline.Gauge with a shear cut every sheet_length_mm. Each coil starts
    with an encoder reset, which the gauge takes as a new strip (a new coil
    number). Returns the gauge's sheets (with their height maps) in order."""
    if not coils:
        raise ValueError("simulate_line() argument 'coils' is empty")
    for i, coil in enumerate(coils):
        if coil.sheets < 1:
            raise ValueError(f"simulate_line() coils[{i}].sheets must be >= 1, got {coil.sheets}")
        if not (coil.thickness_mm > 0 and math.isfinite(coil.thickness_mm)):
            raise ValueError(f"simulate_line() coils[{i}].thickness_mm must be > 0, "
                             f"got {coil.thickness_mm}")
    if not (sheet_length_mm >= 20 * step_mm and math.isfinite(sheet_length_mm)):
        raise ValueError(f"simulate_line() argument 'sheet_length_mm' must be at least 20 rows "
                         f"({20 * step_mm} mm), got {sheet_length_mm}")
    fibers = int(round(width_mm / pitch_mm)) + 1
    calib = flatline.Calibration.reference(first_x_mm=-width_mm / 2, pitch_mm=pitch_mm,
                                           fibers=fibers)
    centre = sum(calib.laser_offsets) / 2  # the row at s: the frame at encoder s + centre
    sheets: List[flatline.Sheet] = []
    thickness: Dict[int, float] = {}
    total = sum(c.sheets for c in coils)
    with flatline.Gauge(calib, rigid_motion=1, gauge_frame_spacing=0.8 * step_mm,
                        gauge_overflow=1, gauge_keep_maps=1) as gauge:
        drive_side_high_x = gauge.option("flat_drive_side") == 1

        def collect() -> None:
            for sheet in gauge:
                sheets.append(sheet)
                if progress:
                    progress(f"  measured sheet {len(sheets)} of {total} "
                             f"(coil {sheet.coil}, sheet {sheet.index})")

        for k, coil in enumerate(coils):
            length = coil.sheets * sheet_length_mm
            if progress:
                progress(f"coil {k + 1} of {len(coils)}: {coil.sheets} sheets, "
                         f"{length / 1000:.1f} m, {coil.thickness_mm:g} mm thick")
            with flatline.SimulatedLine(calib, sim_seed=seed + k, sim_frame_spacing=step_mm,
                                        sim_strip_width=width_mm, sim_heave_sigma=vibration_mm,
                                        sim_peak_sigma=peak_noise_px) as sim:
                for kind, amplitude, period in coil.defects:
                    sim.add_defect(kind, amplitude, period)
                rows = sim.next_rows(int(round(length / step_mm)))
            for r in range(len(rows.s)):
                gauge.push_row(rows.encoder_mm[r], rows.height[r], rows.slope[r], rows.valid[r])
                if r == 0:
                    # After the encoder reset the gauge runs a new strip:
                    # its cuts count from here. (The previous coil's last
                    # sheet ends at this reset.)
                    for cut in np.arange(1, coil.sheets) * sheet_length_mm:
                        gauge.cut(cut + centre)
                collect()
        gauge.flush()  # the end of the input: the last coil's last sheet
        collect()
    # The gauge numbers its strips 1, 2, ...: one per coil, as each coil
    # starts with an encoder reset.
    found = sorted({sheet.coil for sheet in sheets})
    if found != list(range(1, len(coils) + 1)):
        raise RuntimeError(f"the gauge made strips {found} of {len(coils)} simulated coils")
    for sheet in sheets:
        thickness[sheet.coil] = coils[sheet.coil - 1].thickness_mm
    return LineRun(sheets, np.asarray(calib.fiber_x), thickness, drive_side_high_x)


# ---------------------------------------------------------------------------
# Verdicts
# ---------------------------------------------------------------------------

def set_sheet_measures(verdict: flatline.Verdict, sheet: flatline.Sheet) -> None:
    """Gives the verdict the sheet's whole-sheet measures: the largest zone
    I-Units at its zone's centre (sensor x), the largest wave's steepness
    and height at its fiber, bow and crossbow at the strip's centre; s is
    the sheet's middle for all of them (they are not found at one s). A
    NaN measure (its flag set) is "not measured"."""
    s_mid = 0.5 * (sheet.s_start + sheet.s_end)
    zones = np.asarray(sheet.zones.i_units)
    if np.isfinite(zones).any():
        k = int(np.nanargmax(zones))
        zone_x = float(sheet.zones.centre_x[k])
    else:
        zone_x = 0.0
    centre = sheet.strip_centre if math.isfinite(sheet.strip_centre) else 0.0
    wave_x = sheet.wave_x if math.isfinite(sheet.wave_x) else 0.0
    given = (
        (flatline.Measure.ZONE_I_UNITS, sheet.max_i_units, zone_x),
        (flatline.Measure.WAVE_STEEPNESS, sheet.wave_steepness_percent, wave_x),
        (flatline.Measure.WAVE_HEIGHT, sheet.wave_height, wave_x),
        (flatline.Measure.BOW, sheet.bow_mm, centre),
        (flatline.Measure.CROSSBOW, sheet.crossbow_mm, centre),
    )
    for measure, value, x in given:
        verdict.set_measure(measure, value if math.isfinite(value) else None, x, s_mid)


def judge(verdict: flatline.Verdict, sheet: flatline.Sheet, fiber_x: np.ndarray,
          thickness_mm: float, width_mm: Optional[float] = None) -> List[flatline.RuleResult]:
    """One sheet's verdict: its measures (set_sheet_measures) and its height
    map (when the gauge kept it) against every rule, for the coil's
    thickness and the sheet's strip width (or width_mm when given)."""
    if sheet.incomplete:
        # Too many rows missing: judged by no rule, as the gauge does.
        return [flatline.RuleResult(rule, flatline.VerdictState.NOT_JUDGED, math.nan, math.nan,
                                    math.nan, math.nan, math.nan, -1)
                for rule in verdict.rules]
    set_sheet_measures(verdict, sheet)
    width = width_mm if width_mm is not None else sheet.strip_width
    if not math.isfinite(width):
        raise ValueError(f"sheet {sheet.id} has no strip width (its edges are unknown): "
                         f"give width_mm")
    if sheet.z is None or sheet.s is None or sheet.rows < 2:
        return verdict.evaluate(thickness_mm, width)
    return verdict.evaluate(thickness_mm, width, sheet.s, fiber_x, sheet.z, sheet.z_flags)


# ---------------------------------------------------------------------------
# The advisor's suggestions
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Suggestion:
    """One sheet's suggested actuator changes (see README.md, "Advisor's
    suggestions")."""

    sheet: int  #: the Sheet.id it was computed from
    changes: Dict[str, float]  #: actuator name -> change (delta)
    confidence: float  #: in [0, 1]; NaN when the advisor gave none
    units: Dict[str, str] = field(default_factory=dict)  #: actuator name -> unit
    note: str = ""


def read_advice(entries: Optional[Iterable[Mapping[str, Any]]]) -> Dict[int, Suggestion]:
    """Checks the caller's suggestions and indexes them by sheet id. Each
    entry is a mapping {"sheet": Sheet.id, "changes": {actuator: delta},
    "confidence": 0..1, optional "units": {actuator: unit}, optional
    "note": text}. A malformed entry is a ValueError naming it."""
    out: Dict[int, Suggestion] = {}
    if entries is None:
        return out
    for i, entry in enumerate(entries):
        where = f"advice[{i}]"
        if not isinstance(entry, Mapping):
            raise ValueError(f"{where} must be a mapping, not {type(entry).__name__}")
        unknown = set(entry) - {"sheet", "changes", "confidence", "units", "note"}
        if unknown:
            raise ValueError(f"{where} has unknown keys {sorted(unknown)}")
        sheet = entry.get("sheet")
        if not isinstance(sheet, int) or isinstance(sheet, bool):
            raise ValueError(f"{where}['sheet'] must be the sheet's id (an int), got {sheet!r}")
        if sheet in out:
            raise ValueError(f"{where}: sheet {sheet} has a suggestion already")
        changes = entry.get("changes")
        if not isinstance(changes, Mapping):
            raise ValueError(f"{where}['changes'] must map actuator names to changes, "
                             f"got {changes!r}")
        clean: Dict[str, float] = {}
        for name, delta in changes.items():
            if not isinstance(name, str) or not name:
                raise ValueError(f"{where}['changes'] has an actuator name {name!r}")
            try:
                value = float(delta)
            except (TypeError, ValueError):
                raise ValueError(f"{where}['changes'][{name!r}] must be a number, "
                                 f"got {delta!r}") from None
            if not math.isfinite(value):
                raise ValueError(f"{where}['changes'][{name!r}] must be finite, got {delta!r}")
            clean[name] = value
        confidence = entry.get("confidence", math.nan)
        try:
            confidence = float(confidence if confidence is not None else math.nan)
        except (TypeError, ValueError):
            raise ValueError(f"{where}['confidence'] must be a number, "
                             f"got {confidence!r}") from None
        if not (math.isnan(confidence) or 0.0 <= confidence <= 1.0):
            raise ValueError(f"{where}['confidence'] must be in [0, 1], got {confidence}")
        units = entry.get("units", {})
        if not isinstance(units, Mapping) or not all(
                isinstance(k, str) and isinstance(v, str) for k, v in units.items()):
            raise ValueError(f"{where}['units'] must map actuator names to unit strings")
        note = entry.get("note", "")
        if not isinstance(note, str):
            raise ValueError(f"{where}['note'] must be a string")
        out[sheet] = Suggestion(sheet, clean, confidence, dict(units), note)
    return out


# ---------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------

def shape_text(sheet: flatline.Sheet) -> str:
    """The sheet's shape class by the operator's names: the library's
    "left" edge is the drive side's (flatline/flatness.h), whichever
    sensor side that is on."""
    if sheet.shape == flatline.Shape.WAVY_EDGE_DRIVE_SIDE:
        return "wavy edge, drive side"
    if sheet.shape == flatline.Shape.WAVY_EDGE_OPERATOR_SIDE:
        return "wavy edge, operator side"
    return str(sheet.shape)


def _fmt(value: float, unit: str) -> str:
    if value is None or not math.isfinite(value):
        return "–"
    return f"{value:.{DECIMALS.get(unit, 2)}f}"


def _side_labels(ax: Any, high_x_is_drive: bool, axis: str = "y") -> None:
    """Writes DS / OS at the ends of the x axis of a map (sensor x on `axis`)."""
    low, high = ("OS", "DS") if high_x_is_drive else ("DS", "OS")
    names = {"DS": "drive side", "OS": "operator side"}
    if axis == "y":
        ax.text(1.01, 0.0, f"{names[low]}", transform=ax.transAxes, va="bottom",
                ha="left", fontsize=9, rotation=90)
        ax.text(1.01, 1.0, f"{names[high]}", transform=ax.transAxes, va="top",
                ha="left", fontsize=9, rotation=90)


def _height_limit(sheets: Sequence[flatline.Sheet]) -> float:
    """A colour scale common to the coil: the 99.5th percentile of |z|
    (a few wild samples must not wash out the rest), at least 0.05 mm."""
    values = [np.abs(sh.z[np.isfinite(sh.z)]) for sh in sheets if sh.z is not None]
    values = [v for v in values if v.size]
    if not values:
        return 1.0
    return max(float(np.percentile(np.concatenate(values), 99.5)), 0.05)


def _map_axes(ax: Any, fiber_x: np.ndarray, high_x_is_drive: bool) -> None:
    ax.set_ylabel("x across [mm] (sensor)")
    lo, hi = float(fiber_x[0]), float(fiber_x[-1])
    # The drive side at the bottom, whichever sensor side it is on.
    ax.set_ylim((hi, lo) if high_x_is_drive else (lo, hi))


def plot_coil_heights(path: str, coil: int, sheets: Sequence[flatline.Sheet],
                      fiber_x: np.ndarray, failed: Mapping[int, int], high_x_is_drive: bool,
                      limit: float) -> None:
    """The coil's height map, its sheets side by side along s (up to 6 per
    panel), cuts dashed, sheet numbers above (red: failed a rule)."""
    per_row = 6
    groups = [sheets[i:i + per_row] for i in range(0, len(sheets), per_row)]
    fig, axes = plt.subplots(len(groups), 1, figsize=(13, 2.9 * len(groups) + 0.9),
                             squeeze=False, constrained_layout=True)
    norm = TwoSlopeNorm(vcenter=0.0, vmin=-limit, vmax=limit)
    image = None
    # Every panel spans as much strip as the first: one mm is as wide in
    # every row, also in a last row with fewer sheets.
    span = groups[0][-1].s_end - groups[0][0].s_start
    for ax, group in zip(axes[:, 0], groups):
        for sh in group:
            if sh.z is None or sh.s is None or sh.rows < 2:
                continue
            image = ax.pcolormesh(sh.s, fiber_x, sh.z.T, cmap="RdBu_r", norm=norm,
                                  shading="nearest", rasterized=True)
            ax.axvline(sh.s_start, color="k", lw=0.8, ls="--")
            bad = failed.get(sh.id, 0)
            ax.text(0.5 * (sh.s_start + sh.s_end), 1.02, f"sheet {sh.index}",
                    transform=ax.get_xaxis_transform(), ha="center", va="bottom", fontsize=9,
                    color="tab:red" if bad else "black", fontweight="bold" if bad else None)
        ax.set_xlim(group[0].s_start, max(group[0].s_start + span, group[-1].s_end))
        _map_axes(ax, fiber_x, high_x_is_drive)
        _side_labels(ax, high_x_is_drive)
        ax.set_xlabel("s along the coil [mm]")
    if image is not None:
        fig.colorbar(image, ax=axes[:, 0].tolist(), label="height z [mm]", shrink=0.9,
                     pad=0.03)
    fig.suptitle(f"Coil {coil}: reconstructed height map (red sheet numbers failed a rule)")
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_sheet_heights(path: str, sheet: flatline.Sheet, fiber_x: np.ndarray,
                       results: Sequence[flatline.RuleResult], high_x_is_drive: bool,
                       limit: float) -> None:
    """One sheet's height map with the worst point of each straightedge rule
    (the deepest point under the straightedge) marked: a marker per rule,
    red for a failed rule, white for a passed one."""
    fig, ax = plt.subplots(figsize=(11, 5.2), constrained_layout=True)
    norm = TwoSlopeNorm(vcenter=0.0, vmin=-limit, vmax=limit)
    image = ax.pcolormesh(sheet.s, fiber_x, sheet.z.T, cmap="RdBu_r", norm=norm,
                          shading="nearest", rasterized=True)
    fig.colorbar(image, ax=ax, label="height z [mm]", pad=0.07)
    markers = "vs^Dpo*"
    drawn = 0
    for i, r in enumerate(results):
        if r.rule.measure not in LOCAL or r.state not in (flatline.VerdictState.PASS,
                                                          flatline.VerdictState.FAIL):
            continue
        failed = r.state == flatline.VerdictState.FAIL
        # A marker per rule; filled red: failed, white: passed. Not clipped:
        # the worst point is often on the strip's edge.
        # Each later marker smaller: two rules' worst points often coincide
        # (both in the same trough) and must both stay visible.
        ax.plot(r.s_mm, r.x_mm, markers[i % len(markers)], ms=max(18 - 5 * drawn, 6), mew=1.6,
                mfc="tab:red" if failed else "white", mec="black", clip_on=False, zorder=5,
                label=f"{r.rule.name}: {_fmt(r.worst, 'mm')} mm, limit "
                      f"{_fmt(r.limit, 'mm')} mm: {'FAIL' if failed else 'pass'}")
        drawn += 1
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=9,
                  title="worst point of each straightedge rule", title_fontsize=9)
    ax.set_xlim(sheet.s[0], sheet.s[-1])
    _map_axes(ax, fiber_x, high_x_is_drive)
    _side_labels(ax, high_x_is_drive)
    ax.set_xlabel("s along the coil [mm]")
    ax.set_title(f"Coil {sheet.coil}, sheet {sheet.index} (id {sheet.id}), "
                 f"s {sheet.s_start:.0f}–{sheet.s_end:.0f} mm: {shape_text(sheet)}")
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_zone_profiles(path: str, coil: int, sheets: Sequence[flatline.Sheet],
                       i_unit_limits: Sequence[float]) -> None:
    """Every sheet's zone profile in one plot: zones numbered from the drive
    side, a line per sheet coloured by its place in the coil."""
    fig, ax = plt.subplots(figsize=(11, 5.2), constrained_layout=True)
    # viridis without its palest yellow, which fades on white.
    cmap = ListedColormap(plt.get_cmap("viridis")(np.linspace(0.0, 0.9, 256)))
    n = len(sheets)
    zones_max = 0
    for i, sh in enumerate(sheets):
        values = np.asarray(sh.zones.i_units, dtype=float)
        zone = np.arange(1, values.size + 1)
        zones_max = max(zones_max, values.size)
        colour = cmap(i / max(n - 1, 1))
        ax.plot(zone, values, "o-", color=colour, lw=1.6, ms=4,
                label=f"sheet {sh.index} ({shape_text(sh)})")
    for limit in sorted(set(v for v in i_unit_limits if math.isfinite(v))):
        ax.axhline(limit, color="tab:red", ls="--", lw=1.2)
        ax.text(1.0, limit, f" limit {limit:g}", color="tab:red", va="center", ha="left",
                transform=ax.get_yaxis_transform(), fontsize=9)
    if zones_max:
        ax.set_xlim(0.5, zones_max + 0.5)
        ax.set_xticks(np.arange(1, zones_max + 1, 1 if zones_max <= 20 else 2))
    ax.set_ylim(bottom=0)
    ax.set_xlabel("zone  (1 = drive side  →  operator side)")
    ax.set_ylabel("I-Units")
    ax.text(0.0, -0.09, "drive side", transform=ax.transAxes, ha="left", va="top", fontsize=9)
    ax.text(1.0, -0.09, "operator side", transform=ax.transAxes, ha="right", va="top",
            fontsize=9)
    ax.grid(alpha=0.3)
    if n <= 14:
        ax.legend(fontsize=8, ncol=2 if n > 7 else 1, loc="upper left",
                  bbox_to_anchor=(1.06, 1.0), title="sheet", title_fontsize=9)
    else:
        mappable = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(1, n))
        fig.colorbar(mappable, ax=ax, label="sheet in coil", pad=0.06)
    ax.set_title(f"Coil {coil}: zone profile of every sheet")
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_rule_histograms(path: str, coil: int, rules: Sequence[flatline.ToleranceRule],
                         table: Sequence[Sequence[flatline.RuleResult]]) -> None:
    """Per rule, the distribution of its worst value over the coil's
    sheets, with the limit(s) as red dashed lines."""
    n = len(rules)
    cols = min(3, n)
    nrows = int(math.ceil(n / cols))
    fig, axes = plt.subplots(nrows, cols, figsize=(4.4 * cols, 3.1 * nrows),
                             squeeze=False, constrained_layout=True)
    for k, rule in enumerate(rules):
        ax = axes[k // cols, k % cols]
        unit = UNITS[rule.measure]
        worst = np.array([row[k].worst for row in table], dtype=float)
        limits = sorted(set(row[k].limit for row in table if math.isfinite(row[k].limit)))
        worst = worst[np.isfinite(worst)]
        if worst.size == 0:
            ax.text(0.5, 0.5, "not measured on any sheet", ha="center", va="center",
                    transform=ax.transAxes)
            ax.set_xticks([])
            ax.set_yticks([])
        else:
            span = np.concatenate([worst, limits]) if limits else worst
            lo, hi = float(span.min()), float(span.max())
            pad = max(0.08 * (hi - lo), 0.05 * abs(hi), 1e-3)
            bins = np.linspace(lo - pad, hi + pad, 16)
            fails = np.array([row[k].state == flatline.VerdictState.FAIL for row in table])
            values = np.array([row[k].worst for row in table], dtype=float)
            ok = values[~fails & np.isfinite(values)]
            bad = values[fails & np.isfinite(values)]
            ax.hist([ok, bad], bins=bins, stacked=True, color=["tab:green", "tab:red"],
                    label=["pass", "fail"], edgecolor="white")
            for limit in limits:
                ax.axvline(limit, color="tab:red", ls="--", lw=1.4)
                ax.text(limit, 0.97, f"limit {limit:g} ", color="tab:red", fontsize=8,
                        ha="right", va="top", transform=ax.get_xaxis_transform(),
                        bbox=dict(facecolor="white", edgecolor="none", alpha=0.8, pad=1))
            ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
        ax.set_title(rule.name, fontsize=10)
        ax.set_xlabel(f"worst value [{unit}]  (dashed: limit)", fontsize=9)
        ax.set_ylabel("sheets")
        ax.grid(alpha=0.3, axis="y")
    for k in range(n, nrows * cols):
        axes[k // cols, k % cols].axis("off")
    handles: List[Any] = []
    labels: List[str] = []
    for ax in axes.flat:
        handles, labels = ax.get_legend_handles_labels()
        if handles:
            break
    if handles:
        if n < nrows * cols:  # in the first empty panel
            axes[n // cols, n % cols].legend(handles, labels, loc="center", title="sheets")
        else:
            axes[0, 0].legend(handles, labels, fontsize=8)
    fig.suptitle(f"Coil {coil}: each rule's worst value per sheet")
    fig.savefig(path, dpi=100)
    plt.close(fig)


# ---------------------------------------------------------------------------
# The page
# ---------------------------------------------------------------------------

CSS = """
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1350px; color: #222;
       padding: 0 1em; }
h1 { margin-bottom: 0.2em; } h2 { margin-top: 1.6em; border-bottom: 1px solid #bbb; }
p.lead { color: #444; margin-top: 0; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.92em; }
th, td { border: 1px solid #bbb; padding: 0.25em 0.6em; }
th { background: #eee; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.pass td.state, td.pass { background: #cdebcd; }
tr.fail td.state, td.fail { background: #f3bcbc; font-weight: bold; }
tr.fail td.num.margin { color: #a00; font-weight: bold; }
tr.no_band td.state, tr.not_measured td.state, tr.not_judged td.state, td.none,
td.not_judged { background: #e4e4e4; color: #555; }
tr.first td { border-top: 2px solid #777; }
img { max-width: 100%; border: 1px solid #ccc; }
.note { color: #555; font-size: 0.9em; }
.big { font-size: 1.25em; font-weight: bold; }
details { margin: 0.3em 0; } summary { cursor: pointer; }
"""


def _td(text: str, cls: str = "", value: Optional[float] = None) -> str:
    attrs = f' class="{cls}"' if cls else ""
    if value is not None:
        attrs += f' data-value="{value!r}"'
    return f"<td{attrs}>{html.escape(text)}</td>"


def state_text(sheet: flatline.Sheet, result: flatline.RuleResult, thickness_mm: float,
               width_mm: float) -> str:
    """The result cell's text: pass, FAIL, or why the rule did not judge."""
    if result.state == flatline.VerdictState.NO_BAND:
        return f"no band for {thickness_mm:g} × {width_mm:.0f} mm"
    if result.state != flatline.VerdictState.NOT_MEASURED:
        return STATE_TEXT[result.state]
    measure = result.rule.measure
    if measure in LOCAL:
        return "not measured: no height map"
    if measure in (flatline.Measure.WAVE_STEEPNESS, flatline.Measure.WAVE_HEIGHT) and \
            flatline.SheetFlag.NO_WAVE in sheet.flags:
        return "not measured: no wave found"
    return "not measured by the gauge"


def _state_class(state: flatline.VerdictState) -> str:
    return {flatline.VerdictState.PASS: "pass", flatline.VerdictState.FAIL: "fail",
            flatline.VerdictState.NO_BAND: "no_band",
            flatline.VerdictState.NOT_MEASURED: "not_measured",
            flatline.VerdictState.NOT_JUDGED: "not_judged"}[state]


@dataclass
class CoilReport:
    """What write_coil_report wrote and found."""

    coil: int
    path: str  #: the page, <out>/coil_<id>/index.html
    sheets: int
    passed: int  #: sheets every rule judged and passed
    failed: int  #: sheets that failed at least one rule
    results: List[List[flatline.RuleResult]]  #: per sheet, per rule
    not_judged: int = 0  #: sheets no rule failed that a rule could not judge, or incomplete


def write_coil_report(coil: int, sheets: Sequence[flatline.Sheet], out_dir: str,
                      rules: flatline.ToleranceRules, thickness_mm: float,
                      fiber_x: np.ndarray, *, rules_name: str = "",
                      width_mm: Optional[float] = None,
                      advice: Optional[Mapping[int, Suggestion]] = None,
                      drive_side_high_x: bool = False,
                      progress: Optional[Progress] = print) -> CoilReport:
    """Writes <out_dir>/coil_<coil>/index.html and its figures for the
    sheets of one coil (in order). advice: read_advice()'s suggestions, or
    None when no advisor is configured."""
    folder = os.path.join(out_dir, f"coil_{coil}")
    os.makedirs(folder, exist_ok=True)
    rule_list = list(rules)
    verdict = flatline.Verdict(rules)
    table: List[List[flatline.RuleResult]] = []
    for i, sheet in enumerate(sheets):
        if progress:
            progress(f"coil {coil}: judging sheet {i + 1} of {len(sheets)}")
        table.append(judge(verdict, sheet, fiber_x, thickness_mm, width_mm))
    failed = {sh.id: sum(r.state == flatline.VerdictState.FAIL for r in row)
              for sh, row in zip(sheets, table)}

    if progress:
        progress(f"coil {coil}: drawing the coil's figures")
    limit = _height_limit(sheets)
    have_maps = any(sh.z is not None and sh.rows >= 2 for sh in sheets)
    figures = {}
    if have_maps:
        figures["coil"] = "coil_heights.png"
        plot_coil_heights(os.path.join(folder, figures["coil"]), coil, sheets, fiber_x, failed,
                          drive_side_high_x, limit)
    figures["zones"] = "zone_profiles.png"
    i_unit_limits = [row[k].limit for row in table for k, r in enumerate(rule_list)
                     if r.measure == flatline.Measure.ZONE_I_UNITS]
    plot_zone_profiles(os.path.join(folder, figures["zones"]), coil, sheets, i_unit_limits)
    if rule_list:
        figures["hist"] = "rule_histograms.png"
        plot_rule_histograms(os.path.join(folder, figures["hist"]), coil, rule_list, table)
    sheet_png: Dict[int, str] = {}
    for i, (sheet, row) in enumerate(zip(sheets, table)):
        if sheet.z is None or sheet.s is None or sheet.rows < 2:
            continue
        if progress:
            progress(f"coil {coil}: drawing sheet {i + 1} of {len(sheets)}")
        sheet_png[sheet.id] = f"sheet_{sheet.id}_heights.png"
        plot_sheet_heights(os.path.join(folder, sheet_png[sheet.id]), sheet, fiber_x, row,
                           drive_side_high_x, limit)

    _write_csv(os.path.join(folder, "verdicts.csv"), coil, sheets, table)
    page = _page(coil, sheets, table, rule_list, rules_name, thickness_mm, width_mm, figures,
                 sheet_png, advice, drive_side_high_x, limit, fiber_x)
    path = os.path.join(folder, "index.html")
    with open(path, "w", encoding="utf-8") as f:
        f.write(page)
    states = [sheet_state(sh, row) for sh, row in zip(sheets, table)]
    n_passed = sum(st == flatline.VerdictState.PASS for st in states)
    n_failed = sum(st == flatline.VerdictState.FAIL for st in states)
    return CoilReport(coil, path, len(sheets), n_passed, n_failed, table,
                      len(sheets) - n_passed - n_failed)


def _write_csv(path: str, coil: int, sheets: Sequence[flatline.Sheet],
               table: Sequence[Sequence[flatline.RuleResult]]) -> None:
    with open(path, "w", encoding="utf-8", newline="") as f:
        w = csv.writer(f)
        w.writerow(["coil", "sheet_id", "sheet_in_coil", "rule", "measure", "length_mm",
                    "unit", "state", "limit", "worst", "x_mm", "s_mm", "margin", "band"])
        for sheet, row in zip(sheets, table):
            for r in row:
                w.writerow([coil, sheet.id, sheet.index, r.rule.name, r.rule.measure.name.lower(),
                            repr(r.rule.length_mm), UNITS[r.rule.measure],
                            r.state.name.lower(), repr(r.limit), repr(r.worst), repr(r.x_mm),
                            repr(r.s_mm), repr(r.margin), r.band])


def _page(coil: int, sheets: Sequence[flatline.Sheet],
          table: Sequence[Sequence[flatline.RuleResult]],
          rules: Sequence[flatline.ToleranceRule], rules_name: str, thickness_mm: float,
          width_mm: Optional[float], figures: Mapping[str, str], sheet_png: Mapping[int, str],
          advice: Optional[Mapping[int, Suggestion]], high_x_is_drive: bool, limit: float,
          fiber_x: np.ndarray) -> str:
    e = html.escape
    n = len(sheets)

    def width_of(sheet: flatline.Sheet) -> float:
        return width_mm if width_mm is not None else sheet.strip_width

    states = [sheet_state(sh, row) for sh, row in zip(sheets, table)]
    failed_sheets = [sh for sh, st in zip(sheets, states) if st == flatline.VerdictState.FAIL]
    unjudged = [sh for sh, st in zip(sheets, states) if st == flatline.VerdictState.NOT_JUDGED]
    n_passed = n - len(failed_sheets) - len(unjudged)
    length = sum(sh.s_end - sh.s_start for sh in sheets)
    widths = [sh.strip_width for sh in sheets if math.isfinite(sh.strip_width)]
    width_text = f"{np.median(widths):.0f} mm" if widths else "unknown"
    out: List[str] = []
    add = out.append
    add("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">")
    add(f"<title>Coil {coil}: flatness report</title>\n<style>{CSS}</style>\n</head>\n<body>")
    add(f"<h1>Coil {coil}: flatness report</h1>")
    add(f"<p class=\"lead\">{n} sheets, {length / 1000:.1f} m of strip, "
        f"{thickness_mm:g} mm thick, {width_text} wide. Rules: "
        f"<b>{e(rules_name or 'unnamed rule set')}</b>. libflatline {e(flatline.version())}.</p>")
    cls = "fail" if failed_sheets else "pass" if not unjudged else "not_judged"
    add(f"<p class=\"big\" id=\"headline\"><span class=\"{cls}\" style=\"padding:0.1em 0.4em\">"
        f"{n_passed} of {n} sheets within every rule</span>"
        + (f" &nbsp; failed: sheets {', '.join(str(sh.index) for sh in failed_sheets)}"
           if failed_sheets else "")
        + (f" &nbsp; <span class=\"not_judged\">not judged: sheets "
           f"{', '.join(str(sh.index) for sh in unjudged)}</span>" if unjudged else "")
        + "</p>")

    # -- summary per rule
    add("<h2>Summary per rule</h2>")
    add("<table id=\"summary\">\n<tr><th>rule</th><th>measure</th><th>limit</th>"
        "<th>passed</th><th>failed</th><th>not judged</th><th>worst on the coil</th>"
        "<th>at sheet</th><th>median of the sheets</th></tr>")
    for k, rule in enumerate(rules):
        unit = UNITS[rule.measure]
        col = [row[k] for row in table]
        npass = sum(r.state == flatline.VerdictState.PASS for r in col)
        nfail = sum(r.state == flatline.VerdictState.FAIL for r in col)
        other = len(col) - npass - nfail
        limits = sorted(set(r.limit for r in col if math.isfinite(r.limit)))
        finite = [(r.worst, i) for i, r in enumerate(col) if math.isfinite(r.worst)]
        if finite:
            worst, at = max(finite)
            median = float(np.median([w for w, _ in finite]))
            worst_text, at_text = f"{_fmt(worst, unit)} {unit}", str(sheets[at].index)
            median_text = f"{_fmt(median, unit)} {unit}"
        else:
            worst, worst_text, at_text, median_text = math.nan, "–", "–", "–"
        measure = MEASURE_TEXT[rule.measure]
        if rule.length_mm:
            measure += f", {rule.length_mm:g} mm long"
        add(f"<tr class=\"rule\" data-rule=\"{k}\">" + _td(rule.name) + _td(measure)
            + _td(", ".join(f"{_fmt(v, unit)} {unit}" for v in limits) or "no band", "num")
            + _td(str(npass), "num" + (" pass" if npass else ""), npass)
            + _td(str(nfail), "num" + (" fail" if nfail else ""), nfail)
            + _td(str(other), "num" + (" none" if other else ""), other)
            + _td(worst_text, "num", worst if finite else None)
            + _td(at_text, "num") + _td(median_text, "num") + "</tr>")
    add("</table>")
    if "hist" in figures:
        add(f"<p><img src=\"{figures['hist']}\" alt=\"distribution of each rule's worst value "
            f"per sheet\"></p>")

    # -- height map
    add("<h2>Height map</h2>")
    side = "high" if high_x_is_drive else "low"
    if "coil" in figures:
        add(f"<p class=\"note\">The reconstructed heights of the whole coil, sheet after sheet "
            f"(s along travel, x across in sensor coordinates; the drive side is at the "
            f"sensor's {side} x and drawn at the bottom). Colour scale ±{limit:.2f} mm, the "
            f"same for every figure of this coil. Each sheet's own map, with the worst "
            f"point of each straightedge rule, is linked in the table below.</p>")
        add(f"<p><img src=\"{figures['coil']}\" alt=\"height map of coil {coil}\"></p>")
    else:
        add("<p>No height maps: the gauge kept none (gauge_keep_maps = 0); the "
            "straightedge rules are not measured.</p>")

    # -- zone profiles
    add("<h2>Zone profiles</h2>")
    add("<p class=\"note\">I-Units per zone of every sheet, from the drive side to the "
        "operator side; the dashed line is the I-Unit limit where a rule sets one.</p>")
    add(f"<p><img src=\"{figures['zones']}\" alt=\"zone profiles of coil {coil}\"></p>")

    # -- sheets
    add("<h2>Sheets</h2>")
    add("<table id=\"sheets\">\n<tr><th>sheet</th><th>id</th><th>s from [mm]</th>"
        "<th>s to [mm]</th><th>shape</th><th>largest zone [I-Units]</th>"
        "<th>largest wave [mm]</th><th>coverage</th><th>verdict</th><th>rules failed</th>"
        "<th>height map</th></tr>")
    for sh, row, st in zip(sheets, table, states):
        nfail = sum(r.state == flatline.VerdictState.FAIL for r in row)
        verdict_text = {flatline.VerdictState.PASS: "pass", flatline.VerdictState.FAIL: "FAIL",
                        flatline.VerdictState.NOT_JUDGED: "not judged: incomplete"
                        if sh.incomplete else "not judged"}[st]
        png = sheet_png.get(sh.id)
        link = f"<a href=\"{png}\">map</a>" if png else "–"
        add(f"<tr>" + _td(str(sh.index), "num") + _td(str(sh.id), "num")
            + _td(f"{sh.s_start:.0f}", "num") + _td(f"{sh.s_end:.0f}", "num")
            + _td(shape_text(sh)) + _td(_fmt(sh.max_i_units, "I-Units"), "num")
            + _td(_fmt(sh.wave_height, "mm"), "num")
            + _td(f"{100 * sh.coverage:.1f} %", "num" + (" not_judged" if sh.incomplete else ""))
            + _td(verdict_text, _state_class(st))
            + _td(str(nfail), "num " + ("fail" if nfail else "pass"))
            + f"<td>{link}</td></tr>")
    add("</table>")

    # -- verdict table
    add("<h2>Verdicts</h2>")
    add("<p class=\"note\">Per sheet and rule: the limit of the band that applies (by "
        "thickness and width), the worst value, where it is (x across in sensor "
        "coordinates, s along the coil; for a straightedge the deepest point under it), "
        "and the margin (limit − worst: negative fails). Bow, crossbow, waves and zone "
        "I-Units are whole-sheet measures: no s is shown for them, and x only where the "
        "library places them (the largest zone's centre, the largest wave's fiber). "
        "<a href=\"verdicts.csv\">verdicts.csv</a> holds the table at full precision.</p>")
    add("<table id=\"verdicts\">\n<tr><th>sheet</th><th>rule</th><th>limit</th>"
        "<th>worst</th><th>unit</th><th>x [mm]</th><th>s [mm]</th><th>margin</th>"
        "<th>result</th></tr>")
    for sh, row in zip(sheets, table):
        for k, r in enumerate(row):
            unit = UNITS[r.rule.measure]
            first = " first" if k == 0 else ""
            sheet_cell = ""
            if k == 0:
                sheet_cell = (f"<td rowspan=\"{len(row)}\" class=\"num\">"
                              f"{sh.index}<br><span class=\"note\">id {sh.id}</span></td>")
            local = r.rule.measure in LOCAL
            has_x = local or r.rule.measure in (flatline.Measure.ZONE_I_UNITS,
                                                flatline.Measure.WAVE_STEEPNESS,
                                                flatline.Measure.WAVE_HEIGHT)
            x_text = f"{r.x_mm:.0f}" if has_x and math.isfinite(r.x_mm) else "–"
            s_text = f"{r.s_mm:.0f}" if local and math.isfinite(r.s_mm) else (
                "whole sheet" if math.isfinite(r.s_mm) else "–")
            limit_text = _fmt(r.limit, unit) if math.isfinite(r.limit) else "no band"
            add(f"<tr class=\"verdict {_state_class(r.state)}{first}\" data-sheet=\"{sh.id}\" "
                f"data-rule=\"{k}\">" + sheet_cell + _td(r.rule.name)
                + _td(limit_text, "num", r.limit) + _td(_fmt(r.worst, unit), "num", r.worst)
                + _td(unit) + _td(x_text, "num", r.x_mm) + _td(s_text, "num", r.s_mm)
                + _td(_fmt(r.margin, unit), "num margin", r.margin)
                + _td(state_text(sh, r, thickness_mm, width_of(sh)), "state") + "</tr>")
    add("</table>")

    # -- advisor
    add("<h2>Advisor's suggestions</h2>")
    if advice is None:
        add("<p id=\"advice\">No advisor configured: no actuator changes were suggested.</p>")
    else:
        names: List[str] = []
        for sug in advice.values():
            for name in sug.changes:
                if name not in names:
                    names.append(name)
        units: Dict[str, str] = {}
        for sug in advice.values():
            units.update(sug.units)
        add("<p class=\"note\">The actuator changes the advisor proposed after each sheet "
            "(changes to the current settings), with its confidence.</p>")
        add("<table id=\"advice\">\n<tr><th>sheet</th><th>confidence</th>"
            + "".join(f"<th>{e(name)}" + (f" [{e(units[name])}]" if name in units else "")
                      + "</th>" for name in names) + "<th>note</th></tr>")
        for sh in sheets:
            sug = advice.get(sh.id)
            if sug is None:
                add(f"<tr data-sheet=\"{sh.id}\">" + _td(str(sh.index), "num")
                    + f"<td colspan=\"{len(names) + 2}\" class=\"none\">no suggestion</td></tr>")
                continue
            conf = "–" if math.isnan(sug.confidence) else f"{sug.confidence:.2f}"
            add(f"<tr class=\"advice\" data-sheet=\"{sh.id}\">" + _td(str(sh.index), "num")
                + _td(conf, "num", sug.confidence)
                + "".join(_td(f"{sug.changes[name]:+.3g}", "num", sug.changes[name])
                          if name in sug.changes else _td("–", "num") for name in names)
                + _td(sug.note) + "</tr>")
        add("</table>")

    add("<h2>About this page</h2>")
    add(f"<p class=\"note\">Written by tools/coil_report from the gauge's sheets "
        f"(flatline.Gauge) and flatline.Verdict. Coordinates: s along travel (mm, the "
        f"encoder's material coordinate of the coil), x across (mm, sensor coordinates, "
        f"fibers from {fiber_x[0]:.0f} to {fiber_x[-1]:.0f} mm); the drive side is at "
        f"the sensor's {side} x. Heights z in mm.</p>")
    add("</body>\n</html>\n")
    return "\n".join(out)


def _index_page(reports: Sequence[CoilReport], rules_name: str) -> str:
    rows = "".join(
        f"<tr><td><a href=\"coil_{r.coil}/index.html\">coil {r.coil}</a></td>"
        f"<td class=\"num\">{r.sheets}</td><td class=\"num pass\">{r.passed}</td>"
        f"<td class=\"num{' fail' if r.failed else ''}\">{r.failed}</td>"
        f"<td class=\"num{' not_judged' if r.not_judged else ''}\">{r.not_judged}</td></tr>"
        for r in reports)
    return (f"<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>Coil reports</title>\n<style>{CSS}</style>\n</head>\n<body>\n"
            f"<h1>Coil reports</h1>\n<p class=\"lead\">Rules: "
            f"<b>{html.escape(rules_name or 'unnamed rule set')}</b></p>\n"
            f"<table id=\"coils\">\n<tr><th>coil</th><th>sheets</th><th>within every rule</th>"
            f"<th>failed a rule</th><th>not judged</th></tr>\n{rows}\n</table>\n</body>\n"
            f"</html>\n")


def rules_title(path: str) -> str:
    """The rule file's "name" (free text), or its file name."""
    try:
        with open(path, encoding="utf-8") as f:
            name = json.load(f).get("name")
        if isinstance(name, str) and name:
            return name
    except (OSError, ValueError, AttributeError):
        pass
    return os.path.basename(path)


def write_reports(sheets: Sequence[flatline.Sheet], out_dir: str,
                  rules: Union[str, os.PathLike, flatline.ToleranceRules],
                  thickness_mm: Union[float, Mapping[int, float]],
                  fiber_x: Union[np.ndarray, Sequence[float], flatline.Calibration], *,
                  width_mm: Optional[float] = None,
                  advice: Optional[Iterable[Mapping[str, Any]]] = None,
                  drive_side_high_x: bool = False, rules_name: str = "",
                  progress: Optional[Progress] = print) -> List[CoilReport]:
    """Writes one report per coil of `sheets` (grouped by Sheet.coil, in
    order) into out_dir, and out_dir/index.html listing them.

    Args:
        sheets: the gauge's sheets (flatline.Gauge, with gauge_keep_maps >= 1
            for the height maps and the straightedge rules).
        rules: a rule file's path or loaded flatline.ToleranceRules.
        thickness_mm: the strip's thickness, one for every coil or per coil id.
        fiber_x: the height map's columns (sensor x, mm): the calibration's
            fiber grid (a flatline.Calibration gives it).
        width_mm: the width that chooses the rule bands; None: each sheet's
            measured strip width.
        advice: the advisor's suggestions (README.md, "Advisor's
            suggestions"); None: no advisor configured.
        drive_side_high_x: the drive side is at the sensor's high x (the
            gauge's flat_drive_side = 1).
    """
    if isinstance(fiber_x, flatline.Calibration):
        fiber_x = fiber_x.fiber_x
    fiber_x = np.asarray(fiber_x, dtype=float)
    if fiber_x.ndim != 1 or fiber_x.size < 2 or not np.all(np.diff(fiber_x) > 0):
        raise ValueError("write_reports() argument 'fiber_x' must be the (K,) increasing fiber "
                         "positions (mm)")
    if isinstance(rules, flatline.ToleranceRules):
        rule_set = rules
    else:
        rule_set = flatline.ToleranceRules.load(rules)
        rules_name = rules_name or rules_title(os.fspath(rules))
    suggestions = None if advice is None else read_advice(advice)
    coils: Dict[int, List[flatline.Sheet]] = {}
    for sheet in sheets:
        if sheet.z is not None and sheet.z.shape[1] != fiber_x.size:
            raise ValueError(f"sheet {sheet.id} has {sheet.z.shape[1]} fibers, but 'fiber_x' "
                             f"has {fiber_x.size}")
        coils.setdefault(sheet.coil, []).append(sheet)
    if not coils:
        raise ValueError("write_reports() argument 'sheets' is empty")
    os.makedirs(out_dir, exist_ok=True)
    reports = []
    for coil, group in coils.items():
        if isinstance(thickness_mm, Mapping):
            if coil not in thickness_mm:
                raise ValueError(f"write_reports() argument 'thickness_mm' has no thickness "
                                 f"for coil {coil}")
            thickness = float(thickness_mm[coil])
        else:
            thickness = float(thickness_mm)
        mine = None if suggestions is None else {
            sh.id: suggestions[sh.id] for sh in group if sh.id in suggestions}
        report = write_coil_report(coil, group, out_dir, rule_set, thickness, fiber_x,
                                   rules_name=rules_name, width_mm=width_mm, advice=mine,
                                   drive_side_high_x=drive_side_high_x, progress=progress)
        if progress:
            progress(f"coil {coil}: {report.passed} of {report.sheets} sheets within every "
                     f"rule, {report.failed} failed, {report.not_judged} not judged; wrote "
                     f"{report.path}")
        reports.append(report)
    if suggestions is not None:
        known = {sh.id for sh in sheets}
        stray = sorted(set(suggestions) - known)
        if stray:
            raise ValueError(f"advice names sheets {stray} that are not among the sheets")
    with open(os.path.join(out_dir, "index.html"), "w", encoding="utf-8") as f:
        f.write(_index_page(reports, rules_name))
    return reports


# ---------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------

def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description="Runs the simulated line through a flatline.Gauge and writes one HTML "
                    "flatness report per coil (height map, zone profiles, verdicts against a "
                    "rule file, the advisor's suggestions).")
    parser.add_argument("--out", default="coil_report_out", help="output directory")
    parser.add_argument("--rules", default=EXAMPLE_RULES,
                        help="rule file (flatline-tolerances JSON; default: the example beside "
                             "this tool, invented limits)")
    parser.add_argument("--coils", type=int, default=len(DEFAULT_COILS),
                        help=f"simulated coils (1..{len(DEFAULT_COILS)} of the default line)")
    parser.add_argument("--sheets", type=int, default=None,
                        help="sheets per coil (default: 4)")
    parser.add_argument("--sheet-length", type=float, default=3000.0,
                        help="mm between the shear's cuts")
    parser.add_argument("--width", type=float, default=1500.0, help="strip width, mm")
    parser.add_argument("--vibration", type=float, default=1.0,
                        help="sigma of the strip's bounce per frame, mm")
    parser.add_argument("--seed", type=int, default=1, help="noise seed")
    parser.add_argument("--advice", default=None,
                        help="JSON file of the advisor's suggestions (a list of {\"sheet\": id, "
                             "\"changes\": {actuator: delta}, \"confidence\": c})")
    parser.add_argument("--quiet", action="store_true", help="no progress")
    args = parser.parse_args(argv)
    if not 1 <= args.coils <= len(DEFAULT_COILS):
        parser.error(f"--coils must be 1..{len(DEFAULT_COILS)}")
    if args.sheets is not None and args.sheets < 1:
        parser.error("--sheets must be >= 1")
    advice = None
    if args.advice:
        with open(args.advice, encoding="utf-8") as f:
            advice = json.load(f)
        if not isinstance(advice, list):
            parser.error("--advice: the file must hold a JSON list of suggestions")
    progress = None if args.quiet else (lambda text: print(text, flush=True))
    coils = [SimCoil(c.thickness_mm, args.sheets or c.sheets, c.defects)
             for c in DEFAULT_COILS[:args.coils]]
    start = time.perf_counter()
    run = simulate_line(coils, sheet_length_mm=args.sheet_length, width_mm=args.width,
                        vibration_mm=args.vibration, seed=args.seed, progress=progress)
    reports = write_reports(run.sheets, args.out, args.rules, run.thickness_mm, run.fiber_x,
                            advice=advice, drive_side_high_x=run.drive_side_high_x,
                            progress=progress)
    print(f"{len(reports)} coil reports in {time.perf_counter() - start:.1f} s: "
          f"{os.path.join(args.out, 'index.html')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
