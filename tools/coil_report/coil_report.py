#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The coil report: what a quality engineer reads, prints and signs for a
coil, from the archive of the gauge's sheets (flatline.Archive).

    python -m flatline.report ARCHIVE [--coil ID] [--out DIR]

reads a coil from an archive (an SQLite file, or a PostgreSQL connection
string "postgresql://..." / "pg:host=... dbname=..." with Debian's
python3-psycopg2) and writes ``<out>/coil_<id>/index.html`` with PNG figures
beside it, and ``<out>/index.html`` listing the coils written. The page
holds the coil's identity, the summary per rule, a run chart of each rule's
worst value and of the largest I-Units along the coil (limits dashed, leveler
changes marked), the coil's height map, its zone profiles, the failed and
not-judged sheets, every sheet, the advisor's suggestions, and a disposition
and sign-off block; it prints on A4 without splitting a sheet's row, with
the tables' headers repeated and headings kept with what follows them. The
verdicts are the gauge's, read from the archive, never computed again.

Without an archive it runs the simulated line first (three coils, each
with its identity, a leveler change in the middle of each), archives it,
and reports that: a demonstration, and the tool's test. README.md beside
this file has the options and the Python API.
"""

from __future__ import annotations

import argparse
import csv
import html
import json
import math
import os
import sqlite3
import struct
import sys
import time
import zlib
from dataclasses import dataclass, field
from typing import (Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple)

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap, TwoSlopeNorm  # noqa: E402

import flatline  # noqa: E402
from flatline import capi as _capi  # noqa: E402

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

#: Decimals shown for each unit (the CSV and the page's data-value keep all).
DECIMALS = {"mm": 2, "I-Units": 1, "%": 2}

STATE_TEXT = {
    flatline.VerdictState.PASS: "pass",
    flatline.VerdictState.FAIL: "FAIL",
    flatline.VerdictState.NO_BAND: "no band",
    flatline.VerdictState.NOT_MEASURED: "not measured",
    flatline.VerdictState.NOT_JUDGED: "not judged",
}

VERDICT_TEXT = {"pass": "pass", "fail": "FAIL", "not_judged": "not judged",
                "none": "no rules"}


# ---------------------------------------------------------------------------
# The archive (docs/record.md, "The archive")
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class RuleOutcome:
    """One rule's result on one sheet, as the gauge judged it."""

    name: str
    measure: flatline.Measure
    length_mm: float
    state: flatline.VerdictState
    worst: float
    limit: float
    margin: float
    x_mm: float
    s_mm: float
    band: int


@dataclass
class ArchivedSheet:
    """One sheet as the archive holds it."""

    uid: str
    sheet_id: int
    index: int  #: its number in the coil, 1, 2, ...
    utc: float  #: when it was finished, s since 1970
    s_start: float
    s_end: float
    rows: int
    verdict: str  #: "pass", "fail", "not_judged", "none"
    rules_failed: int
    shape: int
    max_i_units: float
    strip_width: float
    flags: int
    thickness_mm: float  #: what chose the bands
    values: np.ndarray  #: every flt_sheet_value by key (NaN beyond those stored)
    zone_i_units: np.ndarray
    zone_centre_x: np.ndarray
    fiber_x: np.ndarray
    rules: List[RuleOutcome] = field(default_factory=list)
    notes: List[Tuple[str, str, float]] = field(default_factory=list)  #: (kind, text, s)
    s: Optional[np.ndarray] = None  #: (rows,) the map's rows, mm
    z: Optional[np.ndarray] = None  #: (rows, K) heights, mm
    z_flags: Optional[np.ndarray] = None

    def value(self, key: int) -> float:
        return float(self.values[key]) if key < len(self.values) else math.nan

    @property
    def coverage(self) -> float:
        return self.value(_capi.FLT_SHEET_COVERAGE)

    @property
    def shape_text(self) -> str:
        return shape_name(self.shape)


@dataclass
class ArchivedCoil:
    """One coil as the archive holds it: its identity and its sheets."""

    uid: str
    line: str
    coil_id: str
    order: str
    heat: str
    grade: str
    customer: str
    thickness_mm: float
    width_mm: float
    gauge_coil: int
    first_utc: float
    last_utc: float
    finished: bool
    extras: Dict[str, str] = field(default_factory=dict)
    sheets: List[ArchivedSheet] = field(default_factory=list)

    @property
    def title(self) -> str:
        return self.coil_id or f"{self.gauge_coil} (no identity given)"


def shape_name(shape: int) -> str:
    """The shape class by the operator's names (the library's "left" edge
    is the drive side's)."""
    try:
        s = flatline.Shape(shape)
    except ValueError:
        return "?"
    if s == flatline.Shape.WAVY_EDGE_DRIVE_SIDE:
        return "wavy edge, drive side"
    if s == flatline.Shape.WAVY_EDGE_OPERATOR_SIDE:
        return "wavy edge, operator side"
    return str(s)


class _Database:
    """SQLite (the standard library) or PostgreSQL (psycopg2), one query
    style: statements are written with "?" and turned into "%s" there."""

    def __init__(self, location: str) -> None:
        self.postgres = location.startswith(("postgresql://", "postgres://", "pg:"))
        if self.postgres:
            try:
                import psycopg2  # Debian: python3-psycopg2
            except ImportError:
                raise SystemExit("reading a PostgreSQL archive needs psycopg2 (Debian: "
                                 "python3-psycopg2)") from None
            self.conn = psycopg2.connect(location[3:] if location.startswith("pg:")
                                         else location)
        else:
            if not os.path.exists(location):
                raise FileNotFoundError(f"no archive at {location}")
            self.conn = sqlite3.connect(location)

    def rows(self, sql: str, params: Sequence[Any] = ()) -> List[Tuple[Any, ...]]:
        cur = self.conn.cursor()
        cur.execute(sql.replace("?", "%s") if self.postgres else sql, tuple(params))
        out = [tuple(bytes(v) if isinstance(v, memoryview) else v for v in row)
               for row in cur.fetchall()]
        cur.close()
        return out

    def close(self) -> None:
        self.conn.close()


def _nan(v: Any) -> float:
    return math.nan if v is None else float(v)


def decode_arrays(blob: bytes) -> Dict[int, np.ndarray]:
    """The sheet's arrays: u32 count, then per array u32 key, u32 n, f64[n]."""
    (count,) = struct.unpack_from("<I", blob, 0)
    at, out = 4, {}
    for _ in range(count):
        key, n = struct.unpack_from("<II", blob, at)
        at += 8
        out[key] = np.frombuffer(blob, "<f8", n, at).copy()
        at += 8 * n
    return out


def _rice(payload: bytes, at: int, n: int, k: int, ub: int, bb: int,
          ne: int) -> np.ndarray:
    unary = np.frombuffer(payload, np.uint8, ub, at)
    binary = np.frombuffer(payload, np.uint8, bb, at + ub)
    escaped = np.frombuffer(payload, "<u8", ne, at + ub + bb)
    ones = np.flatnonzero(np.unpackbits(unary, bitorder="little"))[:n]
    q = np.diff(ones, prepend=-1) - 1
    u = q.astype(np.uint64) << np.uint64(k)
    if k:
        bits = np.unpackbits(binary, bitorder="little")[: n * k].reshape(n, k)
        u |= (bits.astype(np.uint64) * (np.uint64(1) << np.arange(k, dtype=np.uint64))).sum(
            axis=1, dtype=np.uint64)
    u[q == 48] = escaped
    return (u >> np.uint64(1)).astype(np.int64) ^ -(u & np.uint64(1)).astype(np.int64)


def decode_map(blob: bytes) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An archived height map (docs/record.md, "Height maps"): (s, z, flags)."""
    magic, rows, fibers = struct.unpack_from("<III", blob, 0)
    if magic != 0x504D4C46:
        raise ValueError("no height map")
    (quantum,) = struct.unpack_from("<d", blob, 12)
    side_bytes, deflated = struct.unpack_from("<II", blob, 20)
    side = zlib.decompress(blob[28:28 + deflated])
    if len(side) != side_bytes:
        raise ValueError("height map: side data of the wrong size")
    s = np.frombuffer(side, "<f8", rows, 0).copy()
    flags = np.frombuffer(side, np.uint8, rows * fibers, 8 * rows).reshape(rows, fibers)
    at = 28 + deflated
    k = blob[at]
    ub, bb, ne = struct.unpack_from("<III", blob, at + 1)
    e = _rice(blob, at + 13, rows * fibers, k, ub, bb, ne).reshape(fibers, rows)
    q = np.cumsum(np.cumsum(e, axis=1), axis=1)  # second differences along the strip
    z = (q.T * quantum).astype(float)
    z[(flags & 0x80) != 0] = math.nan
    return s, z, flags & 0x7F


def list_coils(location: str) -> List[Tuple[str, str, str, int, float]]:
    """The coils of an archive, newest first: (uid, coil id, grade, sheets,
    first UTC s)."""
    db = _Database(location)
    try:
        return [(r[0], r[1], r[2], int(r[3]), r[4] / 1e9) for r in db.rows(
            "SELECT coil_uid, coil_id, grade, sheets, first_utc_ns FROM coils "
            "ORDER BY first_utc_ns DESC")]
    finally:
        db.close()


def read_coil(location: str, coil: Optional[str] = None, maps: bool = True) -> ArchivedCoil:
    """A coil of the archive with its sheets in order: the one whose coil id
    (or uid) is `coil` (the newest of that id), else the newest coil."""
    db = _Database(location)
    try:
        cols = ("coil_uid, line, coil_id, order_no, heat, grade, customer, "
                "nominal_thickness_mm, nominal_width_mm, gauge_coil, first_utc_ns, "
                "last_utc_ns, finished")
        if coil is None:
            found = db.rows(f"SELECT {cols} FROM coils ORDER BY first_utc_ns DESC LIMIT 1")
        else:
            found = db.rows(f"SELECT {cols} FROM coils WHERE coil_id = ? OR coil_uid = ? "
                            f"ORDER BY first_utc_ns DESC LIMIT 1", (coil, coil))
        if not found:
            raise LookupError(f"the archive has no coil {coil!r}" if coil else
                              "the archive has no coil")
        r = found[0]
        c = ArchivedCoil(r[0], r[1], r[2], r[3], r[4], r[5], r[6], _nan(r[7]), _nan(r[8]),
                         int(r[9]), r[10] / 1e9, r[11] / 1e9, bool(r[12]))
        c.extras = {k: v for k, v in db.rows(
            "SELECT key, value FROM coil_extras WHERE coil_uid = ? ORDER BY position",
            (c.uid,))}
        for row in db.rows(
                "SELECT sheet_uid, sheet_id, sheet_index, utc_ns, s_start_mm, s_end_mm, rows, "
                "verdict, rules_failed, shape, max_i_units, strip_width_mm, flags, thickness_mm, "
                "sheet_values, sheet_arrays, map_codec, map_crc32, map FROM sheets WHERE "
                "coil_uid = ? ORDER BY sheet_index", (c.uid,)):
            arrays = decode_arrays(row[15])
            sh = ArchivedSheet(
                row[0], int(row[1]), int(row[2]), row[3] / 1e9, _nan(row[4]), _nan(row[5]),
                int(row[6]), row[7], int(row[8]), -1 if row[9] is None else int(row[9]),
                _nan(row[10]), _nan(row[11]), int(row[12]), _nan(row[13]),
                np.frombuffer(row[14], "<f8").copy(),
                arrays.get(_capi.FLT_SHEET_ZONE_I_UNITS, np.zeros(0)),
                arrays.get(_capi.FLT_SHEET_ZONE_CENTRE_X, np.zeros(0)),
                arrays.get(_capi.FLT_SHEET_FIBER_X, np.zeros(0)))
            if maps and row[16] == 1 and row[18] is not None:
                blob = bytes(row[18])
                if (zlib.crc32(blob) & 0xFFFFFFFF) != (int(row[17]) & 0xFFFFFFFF):
                    raise ValueError(f"sheet {sh.index}: its map's CRC-32 does not match")
                sh.s, sh.z, sh.z_flags = decode_map(blob)
            for v in db.rows("SELECT name, measure, length_mm, state, worst, limit_value, margin, "
                             "x_mm, s_mm, band FROM verdicts WHERE sheet_uid = ? ORDER BY rule",
                             (sh.uid,)):
                sh.rules.append(RuleOutcome(v[0], flatline.Measure(int(v[1])), _nan(v[2]),
                                            flatline.VerdictState(int(v[3])), _nan(v[4]),
                                            _nan(v[5]), _nan(v[6]), _nan(v[7]), _nan(v[8]),
                                            int(v[9])))
            sh.notes = [(n[0], n[1], _nan(n[2])) for n in db.rows(
                "SELECT kind, text, s_mm FROM notes WHERE sheet_uid = ? ORDER BY position",
                (sh.uid,))]
            c.sheets.append(sh)
        return c
    finally:
        db.close()


# ---------------------------------------------------------------------------
# The advisor's suggestions (unchanged format)
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

def _fmt(value: float, unit: str) -> str:
    if value is None or not math.isfinite(value):
        return "–"
    return f"{value:.{DECIMALS.get(unit, 2)}f}"


def _side_labels(ax: Any, high_x_is_drive: bool) -> None:
    """Writes the sides at the ends of a map's x axis (sensor x on y)."""
    low, high = ("operator side", "drive side") if high_x_is_drive else \
        ("drive side", "operator side")
    ax.text(1.01, 0.0, low, transform=ax.transAxes, va="bottom", ha="left", fontsize=9,
            rotation=90)
    ax.text(1.01, 1.0, high, transform=ax.transAxes, va="top", ha="left", fontsize=9,
            rotation=90)


def _height_limit(sheets: Sequence[ArchivedSheet]) -> float:
    """A colour scale common to the coil: the 99.5th percentile of |z| (a
    few wild samples must not wash out the rest), at least 0.05 mm."""
    values = [np.abs(sh.z[np.isfinite(sh.z)]) for sh in sheets if sh.z is not None]
    values = [v for v in values if v.size]
    if not values:
        return 1.0
    return max(float(np.percentile(np.concatenate(values), 99.5)), 0.05)


def _leveler_changes(coil: ArchivedCoil) -> List[Tuple[float, str]]:
    """The leveler changes noted on the coil's sheets: (s mm, text)."""
    return [(s, text) for sh in coil.sheets for kind, text, s in sh.notes
            if kind == "leveler" and math.isfinite(s)]


def plot_run_chart(path: str, coil: ArchivedCoil) -> None:
    """Each rule's worst value and the largest I-Units along the coil: a
    point per sheet at its middle (red: failed, grey: not judged), the
    limit of the band that applied dashed, leveler changes as vertical
    lines with their text."""
    sheets = coil.sheets
    names = []
    for sh in sheets:
        for r in sh.rules:
            if r.name not in names:
                names.append(r.name)
    panels = names + ["largest zone I-Units (every sheet)"]
    cols = 2 if len(panels) > 3 else 1
    nrows = int(math.ceil(len(panels) / cols))
    fig, grid = plt.subplots(nrows, cols, figsize=(11, 1.45 * nrows + 0.8), sharex=True,
                             squeeze=False, constrained_layout=True)
    axes = grid.reshape(-1, 1)
    for extra in axes[len(panels):, 0]:
        extra.axis("off")
    mid = np.array([0.5 * (sh.s_start + sh.s_end) / 1000.0 for sh in sheets])
    changes = _leveler_changes(coil)
    for ax, name in zip(axes[:, 0], panels):
        if name in names:
            worst, limit, state = [], [], []
            unit = ""
            for sh in sheets:
                r = next((r for r in sh.rules if r.name == name), None)
                worst.append(r.worst if r else math.nan)
                limit.append(r.limit if r else math.nan)
                state.append(r.state if r else flatline.VerdictState.NOT_JUDGED)
                if r:
                    unit = UNITS[r.measure]
            worst_a, limit_a = np.array(worst, float), np.array(limit, float)
            ax.plot(mid, worst_a, "-", color="#888", lw=1)
            colours = ["tab:red" if s == flatline.VerdictState.FAIL else
                       "tab:green" if s == flatline.VerdictState.PASS else "#999" for s in state]
            ax.scatter(mid, worst_a, c=colours, s=22, zorder=3)
            ax.step(mid, limit_a, where="mid", color="tab:red", ls="--", lw=1.2)
            ax.set_ylabel(unit)
            ax.set_title(name, fontsize=9, loc="left")
        else:
            iu = np.array([sh.max_i_units for sh in sheets], float)
            ax.plot(mid, iu, "o-", color="tab:blue", ms=4, lw=1)
            ax.set_ylabel("I-Units")
            ax.set_title(name, fontsize=9, loc="left")
        for s, text in changes:
            ax.axvline(s / 1000.0, color="tab:purple", lw=1.2, ls=":")
        ax.grid(alpha=0.3)
        ax.set_ylim(bottom=0)
        ax.xaxis.set_tick_params(labelbottom=True)
    for s, text in changes:
        axes[0, 0].text(s / 1000.0, 1.0, f" leveler: {text}", color="tab:purple", fontsize=8,
                        va="bottom", ha="left", transform=axes[0, 0].get_xaxis_transform())
    for ax in grid[-1, :]:
        ax.set_xlabel("s along the coil [m]")
    fig.suptitle(f"Coil {coil.title}: worst value per rule along the coil (red: failed, "
                 f"grey: not judged; dashed: the limit; dotted: leveler changes)", fontsize=10)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def plot_coil_heights(path: str, coil: ArchivedCoil, high_x_is_drive: bool,
                      limit: float) -> bool:
    """The coil's height map, its sheets side by side along s (up to 6 per
    panel), cuts dashed, sheet numbers above (red: failed a rule). False
    when no sheet has a map."""
    sheets = [sh for sh in coil.sheets if sh.z is not None and sh.rows >= 2]
    if not sheets:
        return False
    per_row = 6
    groups = [sheets[i:i + per_row] for i in range(0, len(sheets), per_row)]
    fig, axes = plt.subplots(len(groups), 1, figsize=(11, 2.2 * len(groups) + 0.8),
                             squeeze=False, constrained_layout=True)
    norm = TwoSlopeNorm(vcenter=0.0, vmin=-limit, vmax=limit)
    image = None
    span = groups[0][-1].s_end - groups[0][0].s_start
    fiber_x = sheets[0].fiber_x
    for ax, group in zip(axes[:, 0], groups):
        for sh in group:
            x = sh.fiber_x if sh.fiber_x.size == sh.z.shape[1] else np.arange(sh.z.shape[1])
            image = ax.pcolormesh(sh.s / 1000.0, x, sh.z.T, cmap="RdBu_r", norm=norm,
                                  shading="nearest", rasterized=True)
            ax.axvline(sh.s_start / 1000.0, color="k", lw=0.8, ls="--")
            bad = sh.verdict == "fail"
            ax.text(0.5 * (sh.s_start + sh.s_end) / 1000.0, 1.02, f"{sh.index}",
                    transform=ax.get_xaxis_transform(), ha="center", va="bottom", fontsize=9,
                    color="tab:red" if bad else "black", fontweight="bold" if bad else None)
        ax.set_xlim(group[0].s_start / 1000.0,
                    max(group[0].s_start + span, group[-1].s_end) / 1000.0)
        if fiber_x.size:
            lo, hi = float(fiber_x[0]), float(fiber_x[-1])
            ax.set_ylim((hi, lo) if high_x_is_drive else (lo, hi))  # drive side at the bottom
        ax.set_ylabel("x [mm]")
        _side_labels(ax, high_x_is_drive)
        ax.set_xlabel("s along the coil [m]")
    if image is not None:
        fig.colorbar(image, ax=axes[:, 0].tolist(), label="height z [mm]", shrink=0.9, pad=0.03)
    fig.suptitle(f"Coil {coil.title}: reconstructed height map (sheet numbers; red: failed)",
                 fontsize=10)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return True


def plot_zone_profiles(path: str, coil: ArchivedCoil, i_unit_limits: Sequence[float]) -> None:
    """Every sheet's zone profile in one plot: zones numbered from the drive
    side, a line per sheet coloured by its place in the coil."""
    fig, ax = plt.subplots(figsize=(11, 4.2), constrained_layout=True)
    cmap = ListedColormap(plt.get_cmap("viridis")(np.linspace(0.0, 0.9, 256)))
    sheets = coil.sheets
    n = len(sheets)
    zones_max = 0
    for i, sh in enumerate(sheets):
        values = np.asarray(sh.zone_i_units, dtype=float)
        zones_max = max(zones_max, values.size)
        ax.plot(np.arange(1, values.size + 1), values, "o-", color=cmap(i / max(n - 1, 1)),
                lw=1.4, ms=3)
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
    ax.grid(alpha=0.3)
    mappable = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(1, max(n, 2)))
    fig.colorbar(mappable, ax=ax, label="sheet in coil", pad=0.02)
    ax.set_title(f"Coil {coil.title}: zone profile of every sheet")
    fig.savefig(path, dpi=90)
    plt.close(fig)


# ---------------------------------------------------------------------------
# The page
# ---------------------------------------------------------------------------

CSS = """
body { font-family: "DejaVu Sans", sans-serif; margin: 1.2em auto; max-width: 1100px;
       color: #222; padding: 0 1em; font-size: 14px; }
h1 { margin: 0 0 0.2em 0; font-size: 1.7em; }
h2 { margin-top: 1.4em; border-bottom: 1px solid #bbb; font-size: 1.25em; }
p.lead { color: #444; margin-top: 0; }
table { border-collapse: collapse; margin: 0.5em 0; font-size: 0.9em; width: 100%; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.45em; vertical-align: top; }
th { background: #eee; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.pass { background: #cdebcd; }
td.fail { background: #f3bcbc; font-weight: bold; }
td.not_judged, td.none { background: #e4e4e4; color: #555; }
table.identity { width: auto; }
table.identity th { width: 11em; }
img { max-width: 100%; }
.note { color: #555; font-size: 0.88em; }
.big { font-size: 1.2em; font-weight: bold; }
.mark { color: transparent; font-size: 1px; }
.box { display: inline-block; width: 0.9em; height: 0.9em; border: 1px solid #333;
       vertical-align: middle; margin: 0 0.25em 0 0.6em; }
.sign td { height: 2.4em; }
figure { margin: 0.6em 0; }
/* Print: A4; a sheet's row is never split across pages, a table's header
   row repeats on every page it continues on, a heading stays with what
   follows it, a figure is never cut. */
@page { size: A4; margin: 13mm 11mm 14mm 11mm; }
@media print {
  body { margin: 0; max-width: none; font-size: 10pt; padding: 0; }
  a { color: inherit; text-decoration: none; }
  .screen { display: none; }
}
thead { display: table-header-group; }
tfoot { display: table-footer-group; }
tr, td, th { break-inside: avoid; page-break-inside: avoid; }
h1, h2, h3 { break-after: avoid; page-break-after: avoid; }
figure, .keep { break-inside: avoid; page-break-inside: avoid; }
section.sign-off { break-inside: avoid; page-break-inside: avoid; }
"""


def _td(text: str, cls: str = "", value: Optional[float] = None, mark: str = "") -> str:
    attrs = f' class="{cls}"' if cls else ""
    if value is not None:
        attrs += f' data-value="{value!r}"'
    tail = f'<span class="mark">{mark}</span>' if mark else ""
    return f"<td{attrs}>{html.escape(text)}{tail}</td>"


def _state_class(state: flatline.VerdictState) -> str:
    return {flatline.VerdictState.PASS: "pass", flatline.VerdictState.FAIL: "fail"}.get(
        state, "not_judged")


def _utc(t: float) -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(t)) if math.isfinite(t) else "–"


def _runs(sheets: Sequence[ArchivedSheet]) -> List[Tuple[int, int, str]]:
    """Consecutive sheets of the same verdict: (first index, last index,
    verdict)."""
    out: List[Tuple[int, int, str]] = []
    for sh in sheets:
        if out and out[-1][2] == sh.verdict and out[-1][1] == sh.index - 1:
            out[-1] = (out[-1][0], sh.index, sh.verdict)
        else:
            out.append((sh.index, sh.index, sh.verdict))
    return out


def _rule_names(coil: ArchivedCoil) -> List[Tuple[str, flatline.Measure]]:
    names: List[Tuple[str, flatline.Measure]] = []
    for sh in coil.sheets:
        for r in sh.rules:
            if r.name not in [n for n, _ in names]:
                names.append((r.name, r.measure))
    return names


def _sheet_table(table_id: str, sheets: Sequence[ArchivedSheet],
                 rules: Sequence[Tuple[str, flatline.Measure]], caption: str,
                 marker: str) -> List[str]:
    """One row per sheet; each cell of a row ends with a marker (invisible
    1 px text "<marker><index>z", the first cell begins with
    "<marker><index>a") by which the print test finds a row split across
    pages."""
    out = [f'<table id="{table_id}" class="sheets">',
           "<thead><tr><th>sheet</th><th>s [m]</th><th>verdict</th><th>shape</th>"
           "<th>largest I-Units</th><th>coverage</th>"
           + "".join(f"<th>{html.escape(n)} [{UNITS[m]}]</th>" for n, m in rules)
           + "<th>notes</th></tr></thead>", "<tbody>"]
    for sh in sheets:
        z = f"{marker}{sh.index}z"
        cells = [f'<td class="num"><span class="mark">{marker}{sh.index}a</span>{sh.index}'
                 f'<span class="mark">{z}</span></td>',
                 _td(f"{sh.s_start / 1000:.1f}–{sh.s_end / 1000:.1f}", "num", mark=z),
                 _td(VERDICT_TEXT.get(sh.verdict, sh.verdict),
                     {"pass": "pass", "fail": "fail"}.get(sh.verdict, "not_judged"), mark=z),
                 _td(sh.shape_text, mark=z),
                 _td(_fmt(sh.max_i_units, "I-Units"), "num", sh.max_i_units, mark=z),
                 _td("–" if not math.isfinite(sh.coverage) else f"{100 * sh.coverage:.0f} %",
                     "num", mark=z)]
        for name, measure in rules:
            r = next((r for r in sh.rules if r.name == name), None)
            if r is None:
                cells.append(_td("–", "none", mark=z))
                continue
            text = (_fmt(r.worst, UNITS[measure]) if r.state in (
                flatline.VerdictState.PASS, flatline.VerdictState.FAIL) else STATE_TEXT[r.state])
            if r.state == flatline.VerdictState.FAIL:
                text += f" > {r.limit:g}"
            cells.append(_td(text, "num " + _state_class(r.state), r.worst, mark=z))
        notes = "; ".join(f"{kind}: {text}" for kind, text, _ in sh.notes)
        if sh.flags & _capi.FLT_SHEET_FLAG_INCOMPLETE:
            notes = ("incomplete (rows lost): not judged; " + notes).rstrip("; ")
        cells.append(_td(notes, mark=z))
        out.append(f'<tr data-sheet="{sh.index}">' + "".join(cells) + "</tr>")
    out.append("</tbody></table>")
    if caption:
        out.append(f'<p class="note">{caption}</p>')
    return out


@dataclass
class CoilReport:
    """What write_coil_report wrote and found."""

    coil: str
    path: str  #: the page, <out>/coil_<id>/index.html
    sheets: int
    passed: int
    failed: int
    not_judged: int


def _folder_name(coil: ArchivedCoil) -> str:
    ident = coil.coil_id or f"gauge{coil.gauge_coil}"
    safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in ident)
    return f"coil_{safe}"


def write_coil_report(coil: ArchivedCoil, out_dir: str, *,
                      advice: Optional[Mapping[int, Suggestion]] = None,
                      drive_side_high_x: bool = False,
                      progress: Optional[Progress] = print) -> CoilReport:
    """Writes <out_dir>/coil_<id>/index.html and its figures for one
    archived coil. advice: read_advice()'s suggestions by sheet id, or None
    when no advisor is configured."""
    folder = os.path.join(out_dir, _folder_name(coil))
    os.makedirs(folder, exist_ok=True)
    sheets = coil.sheets
    rules = _rule_names(coil)
    if progress:
        progress(f"coil {coil.title}: {len(sheets)} sheets, drawing the figures")
    figures: Dict[str, str] = {}
    if sheets:
        figures["run"] = "run_chart.png"
        plot_run_chart(os.path.join(folder, figures["run"]), coil)
        if plot_coil_heights(os.path.join(folder, "coil_heights.png"), coil, drive_side_high_x,
                             _height_limit(sheets)):
            figures["map"] = "coil_heights.png"
        limits = [r.limit for sh in sheets for r in sh.rules
                  if r.measure == flatline.Measure.ZONE_I_UNITS]
        figures["zones"] = "zone_profiles.png"
        plot_zone_profiles(os.path.join(folder, figures["zones"]), coil, limits)
    _write_csv(os.path.join(folder, "verdicts.csv"), coil)
    page = _page(coil, rules, figures, advice)
    path = os.path.join(folder, "index.html")
    with open(path, "w", encoding="utf-8") as f:
        f.write(page)
    passed = sum(sh.verdict == "pass" for sh in sheets)
    failed = sum(sh.verdict == "fail" for sh in sheets)
    return CoilReport(coil.title, path, len(sheets), passed, failed,
                      len(sheets) - passed - failed)


def _write_csv(path: str, coil: ArchivedCoil) -> None:
    with open(path, "w", encoding="utf-8", newline="") as f:
        w = csv.writer(f)
        w.writerow(["coil_id", "sheet_in_coil", "sheet_id", "verdict", "rule", "measure",
                    "length_mm", "unit", "state", "limit", "worst", "x_mm", "s_mm", "margin",
                    "band"])
        for sh in coil.sheets:
            for r in sh.rules:
                w.writerow([coil.coil_id, sh.index, sh.sheet_id, sh.verdict, r.name,
                            r.measure.name.lower(), repr(r.length_mm), UNITS[r.measure],
                            r.state.name.lower(), repr(r.limit), repr(r.worst), repr(r.x_mm),
                            repr(r.s_mm), repr(r.margin), r.band])


def _page(coil: ArchivedCoil, rules: Sequence[Tuple[str, flatline.Measure]],
          figures: Mapping[str, str], advice: Optional[Mapping[int, Suggestion]]) -> str:
    e = html.escape
    sheets = coil.sheets
    n = len(sheets)
    failed = [sh for sh in sheets if sh.verdict == "fail"]
    unjudged = [sh for sh in sheets if sh.verdict not in ("pass", "fail")]
    passed = n - len(failed) - len(unjudged)
    length = sum(sh.s_end - sh.s_start for sh in sheets if math.isfinite(sh.s_end - sh.s_start))
    out: List[str] = []
    add = out.append
    add('<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">')
    add(f"<title>Coil {e(coil.title)}: flatness report</title>\n<style>{CSS}</style>\n</head>"
        "\n<body>")
    add(f"<h1>Flatness report — coil {e(coil.title)}</h1>")
    add(f'<p class="lead">{n} sheets, {length / 1000:.1f} m of strip, measured '
        f"{e(_utc(coil.first_utc))} to {e(_utc(coil.last_utc))}"
        + (f" on line <b>{e(coil.line)}</b>" if coil.line else "")
        + f". libflatline {e(flatline.version())}.</p>")

    # -- identity
    add('<section class="keep"><h2>Coil</h2><table class="identity" id="identity">')
    rows = [("coil id", coil.coil_id or "(none given)"), ("order", coil.order),
            ("heat", coil.heat), ("grade", coil.grade), ("customer", coil.customer),
            ("nominal thickness", f"{coil.thickness_mm:g} mm" if coil.thickness_mm > 0 else ""),
            ("nominal width", f"{coil.width_mm:g} mm" if coil.width_mm > 0 else ""),
            ("gauge's coil number", str(coil.gauge_coil)),
            ("complete", "yes" if coil.finished else "no: its last sheet is not in the archive")]
    rows += sorted(coil.extras.items())
    for k, v in rows:
        add(f"<tr><th>{e(k)}</th><td>{e(v) if v else '–'}</td></tr>")
    add("</table></section>")

    # -- verdict in one line
    cls = "fail" if failed else "pass" if not unjudged else "not_judged"
    add(f'<p class="big" id="headline"><span class="{cls}" style="padding:0.1em 0.4em">'
        f"{passed} of {n} sheets within every rule</span>"
        + (f" &nbsp; failed: sheets {', '.join(str(sh.index) for sh in failed)}"
           if failed else "")
        + (f' &nbsp; <span class="not_judged">not judged: sheets '
           f"{', '.join(str(sh.index) for sh in unjudged)}</span>" if unjudged else "")
        + "</p>")

    # -- summary per rule
    add('<section class="keep"><h2>Summary per rule</h2><table id="summary"><thead><tr>'
        "<th>rule</th><th>limit</th><th>passed</th><th>failed</th><th>not judged</th>"
        "<th>worst on the coil</th><th>at sheet</th><th>median of the sheets</th></tr></thead>"
        "<tbody>")
    for name, measure in rules:
        res = [(sh, r) for sh in sheets for r in sh.rules if r.name == name]
        unit = UNITS[measure]
        limits = sorted({r.limit for _, r in res if math.isfinite(r.limit)})
        p = sum(r.state == flatline.VerdictState.PASS for _, r in res)
        f_ = sum(r.state == flatline.VerdictState.FAIL for _, r in res)
        judged = [(sh, r) for sh, r in res if r.state in (flatline.VerdictState.PASS,
                                                          flatline.VerdictState.FAIL)]
        worst_sheet, worst = (max(judged, key=lambda t: t[1].worst) if judged else (None, None))
        median = float(np.median([r.worst for _, r in judged])) if judged else math.nan
        add("<tr>" + _td(name) + _td(", ".join(f"{v:g}" for v in limits) + f" {unit}", "num")
            + _td(str(p), "num pass" if p else "num") + _td(str(f_), "num fail" if f_ else "num")
            + _td(str(len(res) - p - f_), "num")
            + _td(_fmt(worst.worst if worst else math.nan, unit) + f" {unit}",
                  "num " + (_state_class(worst.state) if worst else ""))
            + _td(str(worst_sheet.index) if worst_sheet else "–", "num")
            + _td(_fmt(median, unit) + f" {unit}", "num") + "</tr>")
    add("</tbody></table></section>")

    # -- figures
    if "run" in figures:
        add(f'<section class="keep"><h2>Along the coil</h2><figure><img src="{figures["run"]}" '
            f'alt="run chart"></figure><p class="note">Each rule\'s worst value per sheet and the '
            f"largest zone I-Units, at each sheet's middle; the dashed line is the limit of the "
            f"band that applied; dotted lines are leveler changes noted on the line.</p>"
            f"</section>")
    if "map" in figures:
        add(f'<section class="keep"><h2>Height map</h2><figure><img src="{figures["map"]}" '
            f'alt="height map"></figure></section>')
    if "zones" in figures:
        add(f'<section class="keep"><h2>Zone profiles</h2><figure><img src="{figures["zones"]}" '
            f'alt="zone profiles"></figure></section>')

    # -- failed and not judged sheets, then every sheet
    flagged = [sh for sh in sheets if sh.verdict != "pass"]
    add('<h2 id="failed">Failed and not judged sheets</h2>')
    if flagged:
        out.extend(_sheet_table("failed_sheets", flagged, rules, "", "qf"))
    else:
        add("<p>None: every sheet is within every rule.</p>")
    add('<h2 id="all">Every sheet</h2>')
    out.extend(_sheet_table("sheets", sheets, rules,
                            "Per rule: the worst value (FAIL: above the limit shown), or why "
                            "the rule did not judge the sheet. Coverage: rows measured over "
                            "rows expected; below gauge_min_coverage a sheet is not judged.",
                            "qa"))

    # -- advisor
    if advice:
        names = sorted({k for sug in advice.values() for k in sug.changes})
        add('<h2 id="advice-heading">Leveler advisor</h2><table id="advice"><thead><tr>'
            "<th>sheet</th><th>confidence</th>" + "".join(f"<th>{e(x)}</th>" for x in names)
            + "<th>note</th></tr></thead><tbody>")
        for sh in sheets:
            sug = advice.get(sh.sheet_id)
            if sug is None:
                continue
            conf = "–" if math.isnan(sug.confidence) else f"{sug.confidence:.2f}"
            add("<tr>" + _td(str(sh.index), "num") + _td(conf, "num", sug.confidence)
                + "".join(_td(f"{sug.changes[x]:+.3g}", "num", sug.changes[x])
                          if x in sug.changes else _td("–", "num") for x in names)
                + _td(sug.note) + "</tr>")
        add("</tbody></table>")

    # -- disposition and sign-off
    add('<section class="sign-off"><h2 id="disposition">Disposition</h2>')
    add('<p class="note">Per run of sheets with the same verdict, the disposition the quality '
        "engineer decides: tick one, and give the reason for a downgrade or a rejection.</p>")
    add('<table id="disposition-table"><thead><tr><th>sheets</th><th>verdict</th>'
        "<th>disposition</th><th>reason</th></tr></thead><tbody>")
    for first, last, verdict in _runs(sheets):
        rng = f"{first}" if first == last else f"{first}–{last}"
        add("<tr>" + _td(rng, "num") + _td(VERDICT_TEXT.get(verdict, verdict),
                                           {"pass": "pass", "fail": "fail"}.get(verdict,
                                                                                "not_judged"))
            + '<td><span class="box"></span>accept<span class="box"></span>downgrade'
            '<span class="box"></span>reject</td><td></td></tr>')
    add("</tbody></table>")
    add('<table class="sign" id="sign-off"><thead><tr><th>role</th><th>name</th><th>date</th>'
        "<th>signature</th></tr></thead><tbody>"
        "<tr><td>quality engineer</td><td></td><td></td><td></td></tr>"
        "<tr><td>production</td><td></td><td></td><td></td></tr></tbody></table></section>")
    add('<p class="note">Written by flatline.report from the archive of the gauge\'s sheets: '
        "the verdicts are the gauge's, judged as each sheet was finished. s runs along the "
        "coil (mm of the encoder), x across it (sensor coordinates), z up (mm).</p>")
    add("</body>\n</html>\n")
    return "\n".join(out)


def _index_page(reports: Sequence[CoilReport], archive: str) -> str:
    rows = "".join(
        f'<tr><td><a href="{os.path.basename(os.path.dirname(r.path))}/index.html">'
        f"coil {html.escape(r.coil)}</a></td><td class=\"num\">{r.sheets}</td>"
        f'<td class="num pass">{r.passed}</td>'
        f"<td class=\"num{' fail' if r.failed else ''}\">{r.failed}</td>"
        f"<td class=\"num{' not_judged' if r.not_judged else ''}\">{r.not_judged}</td></tr>"
        for r in reports)
    return (f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
            f"<title>Coil reports</title>\n<style>{CSS}</style>\n</head>\n<body>\n"
            f"<h1>Coil reports</h1>\n<p class=\"lead\">From {html.escape(archive)}</p>\n"
            f'<table id="coils"><thead><tr><th>coil</th><th>sheets</th><th>within every rule'
            f"</th><th>failed a rule</th><th>not judged</th></tr></thead><tbody>\n{rows}\n"
            f"</tbody></table>\n</body>\n</html>\n")


def write_reports(archive: str, out_dir: str, coils: Optional[Sequence[str]] = None, *,
                  advice: Optional[Iterable[Mapping[str, Any]]] = None,
                  drive_side_high_x: bool = False,
                  progress: Optional[Progress] = print) -> List[CoilReport]:
    """Writes one report per coil of an archive (all of them, newest first,
    or those whose ids are `coils`) and out_dir/index.html listing them.
    advice: the advisor's suggestions (README.md), by the sheets' ids."""
    suggestions = None if advice is None else read_advice(advice)
    os.makedirs(out_dir, exist_ok=True)
    wanted = list(coils) if coils else [uid for uid, *_ in list_coils(archive)]
    reports = []
    for ident in wanted:
        coil = read_coil(archive, ident)
        reports.append(write_coil_report(coil, out_dir, advice=suggestions,
                                         drive_side_high_x=drive_side_high_x,
                                         progress=progress))
    with open(os.path.join(out_dir, "index.html"), "w", encoding="utf-8") as f:
        f.write(_index_page(reports, archive))
    return reports


# ---------------------------------------------------------------------------
# The simulated line, archived
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class SimCoil:
    """One simulated coil: its identity, the sheets the shear cuts it into,
    its defects, each (kind, amplitude mm, period mm) as
    flatline.SimulatedLine.add_defect takes them, and the leveler change
    noted in its middle (the defects' amplitude halves there, as a leveler
    that was set right would do)."""

    coil: flatline.CoilInfo
    sheets: int
    defects: Tuple[Tuple[str, float, float], ...]
    leveler_change: str = "entry rolls +0.3 mm"


#: The default line: three coils, a mild centre buckle, a long drive-side
#: edge, long quarters with coil set and crossbow.
DEFAULT_COILS = (
    SimCoil(flatline.CoilInfo("SIM-4711", order="PO-2026-117", heat="H 88123", grade="S355MC",
                              customer="Acme Trailers", thickness_mm=3.0, width_mm=1500.0,
                              extras={"line": "CTL 2"}),
            4, (("centre_buckle", 1.6, 1800.0), ("centre_buckle", 0.9, 2300.0))),
    SimCoil(flatline.CoilInfo("SIM-4712", order="PO-2026-118", heat="H 88124", grade="S235JR",
                              customer="Nordbau", thickness_mm=5.0, width_mm=1500.0),
            4, (("wavy_edge_left", 4.0, 1200.0), ("wavy_edge_left", 2.0, 1450.0),
                ("centre_buckle", 0.5, 1800.0))),
    SimCoil(flatline.CoilInfo("SIM-4713", order="PO-2026-119", heat="H 88125", grade="S700MC",
                              customer="Acme Trailers", thickness_mm=8.0, width_mm=1500.0),
            4, (("quarter_buckle", 1.2, 1600.0), ("quarter_buckle", 0.6, 1900.0),
                ("bow", 6.0, 9000.0), ("crossbow", 1.2, 0.0))),
)


def simulate_line(archive: str, rules_path: str = EXAMPLE_RULES,
                  coils: Sequence[SimCoil] = DEFAULT_COILS, sheet_length_mm: float = 3000.0,
                  width_mm: float = 1500.0, pitch_mm: float = 10.0, step_mm: float = 3.0,
                  vibration_mm: float = 1.0, peak_noise_px: float = 1 / 16, seed: int = 1,
                  progress: Optional[Progress] = print) -> List[flatline.Sheet]:
    """Runs the simulated line through one flatline.Gauge judged by the
    rule file and archived into `archive` (created if needed): per coil its
    identity (flatline.CoilInfo), a SimulatedLine with its defects, a shear
    cut every sheet_length_mm and a leveler change noted in the middle,
    after which the defects are half as large. Each coil starts with an
    encoder reset (a new strip). Returns the gauge's sheets (as the caller
    of a gauge reads them: their verdicts are the ones archived)."""
    if not coils:
        raise ValueError("simulate_line() argument 'coils' is empty")
    for i, c in enumerate(coils):
        if c.sheets < 1:
            raise ValueError(f"simulate_line() coils[{i}].sheets must be >= 1, got {c.sheets}")
    if not (sheet_length_mm >= 20 * step_mm and math.isfinite(sheet_length_mm)):
        raise ValueError(f"simulate_line() argument 'sheet_length_mm' must be at least 20 rows "
                         f"({20 * step_mm} mm), got {sheet_length_mm}")
    fibers = int(round(width_mm / pitch_mm)) + 1
    calib = flatline.Calibration.reference(first_x_mm=-width_mm / 2, pitch_mm=pitch_mm,
                                           fibers=fibers)
    centre = sum(calib.laser_offsets) / 2
    rules = flatline.ToleranceRules.load(rules_path)
    total = sum(c.sheets for c in coils)
    done = 0
    measured: List[flatline.Sheet] = []
    with flatline.Archive(archive, line="simulated line") as ar, \
            flatline.Gauge(calib, rigid_motion=1, gauge_frame_spacing=0.8 * step_mm,
                           gauge_keep_maps=1) as gauge:
        gauge.attach_archive(ar)
        gauge.set_rules(rules, thickness_mm=coils[0].coil.thickness_mm or 3.0,
                        width_mm="measured")

        def collect() -> None:
            nonlocal done
            for sheet in gauge:
                done += 1
                measured.append(sheet)
                if progress:
                    progress(f"  measured sheet {done} of {total} (coil "
                             f"{sheet.coil_info.coil_id if sheet.coil_info else sheet.coil}, "
                             f"sheet {sheet.index})")

        for k, c in enumerate(coils):
            length = c.sheets * sheet_length_mm
            if progress:
                progress(f"coil {c.coil.coil_id} ({k + 1} of {len(coils)}): {c.sheets} sheets, "
                         f"{length / 1000:.1f} m, {c.coil.thickness_mm:g} mm {c.coil.grade}")
            gauge.set_coil(c.coil)
            n_rows = int(round(length / step_mm))
            half = n_rows // 2
            parts = []
            for scale, rows in ((1.0, half), (0.5, n_rows - half)):
                with flatline.SimulatedLine(calib, sim_seed=seed + k, sim_frame_spacing=step_mm,
                                            sim_strip_width=width_mm,
                                            sim_heave_sigma=vibration_mm,
                                            sim_peak_sigma=peak_noise_px,
                                            sim_start=(0.0 if scale == 1.0
                                                       else half * step_mm)) as sim:
                    for kind, amplitude, period in c.defects:
                        sim.add_defect(kind, amplitude * scale, period)
                    parts.append(sim.next_rows(rows))
            for p, part in enumerate(parts):
                for r in range(len(part.s)):
                    if p == 1 and r == 0:
                        gauge.note("leveler", c.leveler_change)
                    gauge.push_row(part.encoder_mm[r], part.height[r], part.slope[r],
                                   part.valid[r])
                    if p == 0 and r == 0:
                        for cut in np.arange(1, c.sheets) * sheet_length_mm:
                            gauge.cut(cut + centre)
                    collect()
        gauge.flush()
        collect()
        gauge.attach_archive(None)
        ar.flush()
    return measured


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m flatline.report",
        description="The coil report from the archive of a gauge's sheets (flatline.Archive); "
                    "without an archive, the simulated line is archived and reported.")
    parser.add_argument("archive", nargs="?",
                        help="the archive: an SQLite file, or a PostgreSQL connection string "
                             "(postgresql://... or pg:host=... dbname=...)")
    parser.add_argument("--coil", action="append", default=None,
                        help="a coil id to report (repeatable; default: every coil)")
    parser.add_argument("--out", default="coil_report_out", help="output directory")
    parser.add_argument("--advice", help="the advisor's suggestions, a JSON list")
    parser.add_argument("--drive-side", choices=("low_x", "high_x"), default="low_x",
                        help="where the drive side is across the sensor (the gauge's "
                             "flat_drive_side; default low_x)")
    sim = parser.add_argument_group("the simulated line (without an archive)")
    sim.add_argument("--rules", default=EXAMPLE_RULES, help="the rule file")
    sim.add_argument("--coils", type=int, default=3, help="how many of the three coils")
    sim.add_argument("--sheets", type=int, default=4, help="sheets per coil")
    sim.add_argument("--sheet-length", type=float, default=3000.0, help="mm between cuts")
    sim.add_argument("--width", type=float, default=1500.0, help="strip width, mm")
    sim.add_argument("--vibration", type=float, default=1.0, help="sigma of the bounce, mm")
    sim.add_argument("--seed", type=int, default=1, help="noise seed")
    parser.add_argument("--quiet", action="store_true", help="no progress")
    args = parser.parse_args(argv)
    progress = None if args.quiet else print
    if args.coils < 1 or args.coils > len(DEFAULT_COILS):
        parser.error(f"--coils must be 1..{len(DEFAULT_COILS)}")
    if args.sheets < 1:
        parser.error("--sheets must be at least 1")
    archive = args.archive
    if archive is None:
        os.makedirs(args.out, exist_ok=True)
        archive = os.path.join(args.out, "archive.sqlite")
        if os.path.exists(archive):
            os.remove(archive)
        coils = [SimCoil(c.coil, args.sheets, c.defects, c.leveler_change)
                 for c in DEFAULT_COILS[:args.coils]]
        simulate_line(archive, args.rules, coils, args.sheet_length, args.width,
                      vibration_mm=args.vibration, seed=args.seed, progress=progress)
    advice = None
    if args.advice:
        with open(args.advice, encoding="utf-8") as f:
            advice = json.load(f)
    reports = write_reports(archive, args.out, args.coil, advice=advice,
                            drive_side_high_x=args.drive_side == "high_x", progress=progress)
    for r in reports:
        print(f"coil {r.coil}: {r.sheets} sheets, {r.passed} within every rule, {r.failed} "
              f"failed, {r.not_judged} not judged: {r.path}")
    print(f"wrote {os.path.join(args.out, 'index.html')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
