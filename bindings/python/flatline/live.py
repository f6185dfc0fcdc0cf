# SPDX-License-Identifier: Apache-2.0
"""The live view: a local web page showing what the gauge sees while the
lasers are aligned and the exposure is set.

    python -m flatline.live                      # the simulated line
    python -m flatline.live --camera u3v --calib sensor.json
    python -m flatline.live --camera 192.168.3.10 --calib sensor.json --rules rules.json

(installed as the command ``flatline-live``). It prints the page's address,
``http://127.0.0.1:8090/`` by default; open it in a browser. The page shows

- the camera frame (or the simulator's) with the extracted lines (laser 0
  green, laser 1 blue), their bands of rows (dashed), the saturated pixels
  (red) and the strip's edges (orange) drawn in, refreshed several times a
  second;
- per laser: the band, the columns with a line, how many of them are
  saturated, the line's and the background's level (contrast) and the
  strip's edges in mm;
- counters: frames and their rate, the source's drops, losses and
  timeouts, the gauge's frames, skips, drops and sheets;
- the last sheets: height map, zone bars (I-Units from the drive side to the
  operator side) and, with a rule file, the verdict of each rule.

The server listens on the loopback interface only unless ``--listen``
names another address (the page has no login: put it only on a network
you trust). It needs nothing beyond the flatline package and numpy: no
browser plug-in, no script from the internet.

Frames come from the simulated sensor (``--simulate``, the default), a
camera (``--camera``, as flatline-camera's ``-c``: ``u3v``, ``u3v:SERIAL``,
``gige:ADDRESS|SERIAL``, an IPv4 address) or a folder of images
(``--images``). One thread acquires and pushes every frame into a
:class:`flatline.Gauge`; another takes the newest frame a few times a
second, runs its own :class:`flatline.Extractor` on it and draws the
overlay, and collects the gauge's sheets. Frames the page never shows are
still measured.
"""

from __future__ import annotations

import argparse
import collections
import html
import json
import math
import os
import re
import struct
import sys
import threading
import time
import zlib
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, Deque, Dict, List, Optional, Sequence, Tuple

import numpy as np

import flatline

__all__ = ["LiveView", "main", "png_bytes", "render_overlay"]

#: Overlay colours (the page's legend says the same).
LINE_COLOURS = ((0, 255, 0), (0, 170, 255))
BAND_COLOURS = ((0, 120, 0), (0, 80, 140))
SATURATED = (255, 0, 0)
EDGE = (255, 150, 0)

#: How often the overlay is redrawn, s: fast enough to follow a laser being
#: turned by hand, slow enough to leave the CPU to the gauge.
OVERLAY_PERIOD_S = 0.25
#: Sheets kept for the page.
SHEETS_SHOWN = 6


# ---------------------------------------------------------------------------
# Pictures
# ---------------------------------------------------------------------------

def png_bytes(image: np.ndarray, level: int = 1) -> bytes:
    """A PNG file of an (h, w) uint8 grey or (h, w, 3) uint8 RGB image
    (zlib level 1: a frame a few times a second costs a few ms)."""
    image = np.ascontiguousarray(image, dtype=np.uint8)
    if image.ndim == 2:
        colour, rows = 0, image
    elif image.ndim == 3 and image.shape[2] == 3:
        colour, rows = 2, image.reshape(image.shape[0], -1)
    else:
        raise ValueError(f"png_bytes() wants (h, w) or (h, w, 3), got {image.shape}")
    h, w = image.shape[0], image.shape[1]
    raw = np.empty((h, rows.shape[1] + 1), dtype=np.uint8)
    raw[:, 0] = 0  # filter: none
    raw[:, 1:] = rows

    def chunk(kind: bytes, body: bytes) -> bytes:
        return (struct.pack(">I", len(body)) + kind + body
                + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))

    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw.tobytes(), level))
            + chunk(b"IEND", b""))


def _grey8(frame: np.ndarray, bits: int) -> np.ndarray:
    if frame.dtype == np.uint8:
        return frame
    return (frame >> max(bits - 8, 0)).astype(np.uint8)


def _edge_column(calib: flatline.Calibration, laser: int, rows: np.ndarray,
                 x_mm: float) -> float:
    """The image column of the strip's edge at x_mm on the laser's line:
    the edge on the laser plane at the height of the line's column nearest
    it, mapped into the image; NaN without one."""
    cols = np.flatnonzero(np.isfinite(rows))
    if not math.isfinite(x_mm) or cols.size == 0:
        return math.nan
    plane = calib.image_to_plane(laser, np.column_stack([cols, rows[cols]]).astype(float))
    ok = np.isfinite(plane[:, 0])
    if not ok.any():
        return math.nan
    nearest = np.flatnonzero(ok)[np.argmin(np.abs(plane[ok, 0] - x_mm))]
    u = calib.plane_to_image(laser, np.array([[x_mm, plane[nearest, 1]]]))[0, 0]
    return float(u)


def render_overlay(frame: np.ndarray, bits: int, extractor: flatline.Extractor,
                   calib: flatline.Calibration) -> Tuple[np.ndarray, Dict[str, Any]]:
    """The frame in grey with what the extractor found drawn in, and the
    figures per laser: band, columns with a line, saturated ones, line and
    background levels (fractions of full scale), strip edges (mm and
    column). A frame the extractor refuses (no line it can place an
    automatic band from) is drawn with its saturated pixels only, and says
    why."""
    full = (1 << bits) - 1
    grey = _grey8(frame, bits)
    rgb = np.repeat(grey[:, :, None], 3, axis=2)
    saturated = frame >= full
    info: Dict[str, Any] = {"saturated_pixels": int(saturated.sum()), "lasers": [],
                            "error": ""}
    try:
        extractor.process(frame, 0.0)
        peaks = extractor.peaks()
    except flatline.FlatlineError as exc:
        info["error"] = str(exc)
        rgb[saturated] = SATURATED
        return rgb, info
    h, w = frame.shape
    columns = np.arange(w)
    for laser in (0, 1):
        first, n = extractor.band(laser)
        last = min(first + n, h) - 1
        dashes = (columns // 8) % 2 == 0
        rgb[first, dashes] = BAND_COLOURS[laser]
        rgb[last, dashes] = BAND_COLOURS[laser]
        band_sat = saturated[first:last + 1]
        rgb[first:last + 1][band_sat] = SATURATED
        rows = peaks[laser]
        valid = np.isfinite(rows)
        r = np.clip(np.rint(rows[valid]).astype(int), 0, h - 1)
        rgb[r, columns[valid]] = LINE_COLOURS[laser]
        # contrast: the pixel at the line against the band's pixels 8..16
        # rows away, medians over the columns with a line
        line_level = background = math.nan
        if valid.any():
            c = columns[valid]
            line_level = float(np.median(frame[r, c])) / full
            offsets = np.concatenate([np.arange(-16, -7), np.arange(8, 17)])
            yy = r[:, None] + offsets[None, :]
            inside = (yy >= first) & (yy <= last)
            values = np.where(inside, frame[np.clip(yy, 0, h - 1), c[:, None]], np.nan)
            with np.errstate(invalid="ignore"):
                per_column = np.nanmean(values, axis=1)
            if np.isfinite(per_column).any():
                background = float(np.nanmedian(per_column)) / full
        edges = extractor.strip(laser)
        sat = extractor.saturation(laser)
        edge_u = []
        for x in (edges.left_mm, edges.right_mm):
            u = _edge_column(calib, laser, rows, x)
            edge_u.append(u)
            if math.isfinite(u):
                ui = int(round(u))
                rgb[first:last + 1, max(ui - 1, 0):min(ui + 2, w)] = EDGE
        info["lasers"].append({
            "laser": laser, "band": [int(first), int(last)],
            "peaks": int(sat.peaks), "saturated": int(sat.saturated),
            "saturated_fraction": float(sat.fraction),
            "line_level": line_level, "background_level": background,
            "contrast": (line_level - background
                         if math.isfinite(line_level) and math.isfinite(background)
                         else math.nan),
            "strip_left_mm": edges.left_mm, "strip_right_mm": edges.right_mm,
            "strip_left_column": edge_u[0], "strip_right_column": edge_u[1],
            "strip_flags": int(edges.flags),
        })
    return rgb, info


def _height_map_png(sheet: flatline.Sheet) -> Tuple[bytes, float, float]:
    """The sheet's reconstructed heights as a PNG (rows along travel down,
    fibers across), blue low, white level, red high around the sheet's
    median, and the colour scale's ends, mm. No data is grey."""
    z = np.asarray(sheet.z, dtype=float)
    finite = np.isfinite(z)
    if not finite.any():
        return png_bytes(np.full((max(z.shape[0], 1), max(z.shape[1], 1)), 128, np.uint8)), \
            math.nan, math.nan
    centre = float(np.median(z[finite]))
    span = float(np.percentile(np.abs(z[finite] - centre), 99)) or 1e-3
    t = np.clip((np.where(finite, z, centre) - centre) / span, -1.0, 1.0)
    rgb = np.empty(z.shape + (3,), dtype=np.uint8)
    low, high = t < 0, t >= 0
    # blue (40, 80, 200) .. white .. red (200, 40, 40)
    for channel, (lo, hi) in enumerate(((40, 200), (80, 40), (200, 40))):
        v = np.empty(z.shape)
        v[low] = 255 + (255 - lo) * t[low]
        v[high] = 255 - (255 - hi) * t[high]
        rgb[:, :, channel] = np.clip(v, 0, 255).astype(np.uint8)
    rgb[~finite] = (128, 128, 128)
    # at most 400 rows on the page: keep every k-th row
    step = max(1, z.shape[0] // 400)
    return png_bytes(rgb[::step]), centre - span, centre + span


def _finite(x: float) -> Optional[float]:
    return float(x) if x is not None and math.isfinite(x) else None


def _sheet_summary(sheet: flatline.Sheet, scale: Tuple[float, float]) -> Dict[str, Any]:
    verdict = []
    for result in sheet.verdict or ():
        verdict.append({"rule": result.rule.name, "state": result.state.name.lower(),
                        "worst": _finite(result.worst), "limit": _finite(result.limit)})
    zones = [{"x": _finite(x), "i_units": _finite(i)}
             for x, i in zip(sheet.zones.centre_x.tolist(), sheet.zones.i_units.tolist())]
    return {
        "id": sheet.id, "coil": sheet.coil, "index": sheet.index,
        "length_mm": _finite(sheet.s_end - sheet.s_start), "rows": sheet.rows,
        "max_i_units": _finite(sheet.max_i_units), "shape": sheet.shape.name.lower(),
        "strip_width_mm": _finite(sheet.strip_width),
        "rules": len(verdict), "failed": sheet.failed_rules, "verdict": verdict,
        "state": sheet.verdict_state.name.lower(), "provisional": sheet.provisional,
        "zones": zones, "scale_mm": [_finite(scale[0]), _finite(scale[1])],
    }


# ---------------------------------------------------------------------------
# Frames in
# ---------------------------------------------------------------------------

class _Simulated:
    """The simulated line: a strip narrower than the field of view on the
    roller table, a centre buckle, a bounce, a shear cut every sheet."""

    def __init__(self, calib: flatline.Calibration, args: argparse.Namespace) -> None:
        self.sim = flatline.SimulatedLine(
            calib, sim_seed=args.seed, sim_frame_spacing=args.frame_spacing,
            sim_surround=2, sim_strip_width=args.strip_width, sim_strip_offset=50.0,
            sim_heave_sigma=0.2, sim_peak_sigma=1 / 16, sim_line_peak=0.95)
        self.sim.add_defect("centre_buckle", 3.0, 1800.0)
        self.sim.add_defect("wavy_edge_both", 2.0, 900.0)
        self.image: Optional[np.ndarray] = None
        self.bits = int(self.sim.pixel_format)
        self.description = (f"simulated line: {args.strip_width:g} mm strip, centre buckle and "
                            f"wavy edges, a frame every {args.frame_spacing:g} mm")

    def next(self) -> Tuple[np.ndarray, float]:
        frame = self.sim.next_frame(self.image)
        self.image = frame.image
        return frame.image, frame.encoder_mm

    def counters(self) -> Dict[str, int]:
        return {}

    def close(self) -> None:
        self.sim.close()


class _FromSource:
    """A camera or a folder of images through flatline.Source."""

    def __init__(self, source: flatline.Source, description: str) -> None:
        self.source = source
        self.description = description
        self.bits = 8
        source.start()

    def next(self) -> Optional[Tuple[np.ndarray, float]]:
        try:
            frame = self.source.next(1000)
        except flatline.TimeoutError:
            return None
        if frame is None:
            raise EOFError("the end of the images")
        self.bits = int(frame.pixel_format)
        return frame.pixels, frame.encoder_mm

    def counters(self) -> Dict[str, int]:
        return {k: v for k, v in self.source.counters().items()
                if k in ("frames", "dropped", "lost", "timeouts", "packets_missing",
                         "packets_resent")}

    def close(self) -> None:
        try:
            self.source.stop()
        finally:
            self.source.close()


def _open_camera(selector: str) -> flatline.Source:
    if selector == "u3v":
        return flatline.Source.u3v()
    if selector.startswith("u3v:"):
        return flatline.Source.u3v(selector[4:])
    if selector.startswith("gige:"):
        return flatline.Source.gige(selector[5:])
    if re.fullmatch(r"\d+\.\d+\.\d+\.\d+(:\d+)?", selector):
        return flatline.Source.gige(selector)
    try:
        return flatline.Source.u3v(selector)
    except flatline.NotFoundError:
        return flatline.Source.gige(selector)


# ---------------------------------------------------------------------------
# The live view
# ---------------------------------------------------------------------------

class LiveView:
    """Frames into a gauge on one thread, the overlay and the sheets on
    another, and their latest state for the page (:meth:`state`,
    :meth:`overlay_png`, :meth:`sheet_png`)."""

    def __init__(self, frames: Any, calib: flatline.Calibration, *,
                 rules: Optional[flatline.ToleranceRules] = None, thickness_mm: float = 3.0,
                 width_mm: float = 0.0, cut_every_mm: float = 0.0,
                 gauge_options: Optional[Dict[str, float]] = None) -> None:
        self.frames = frames
        self.calib = calib
        self.cut_every_mm = cut_every_mm
        options = {"gauge_keep_maps": 1, "gauge_overflow": 0}
        options.update(gauge_options or {})
        self.gauge = flatline.Gauge(calib, **options)
        if rules is not None:
            # width 0: each sheet's measured strip width chooses the band
            self.gauge.set_rules(rules, thickness_mm, width_mm if width_mm > 0 else "measured")
        self.rules_name = ""
        self.extractor = flatline.Extractor(calib)
        self._lock = threading.Lock()
        self._latest: Optional[Tuple[np.ndarray, float, int]] = None
        self._want = True
        self._first_overlay_s: Optional[float] = None
        self._frames = 0
        self._started = time.monotonic()
        self._overlay = b""
        self._overlay_seq = 0
        self._overlay_info: Dict[str, Any] = {}
        self._raw = b""
        self._sheets: Deque[Dict[str, Any]] = collections.deque(maxlen=SHEETS_SHOWN)
        self._sheet_png: Dict[int, bytes] = {}
        self._error = ""
        # the source has no more frames (the end of a folder of images): a
        # state, not an error; the view keeps the last picture
        self._finished = ""
        self._stop = threading.Event()
        self._next_cut = cut_every_mm
        self._first_encoder: Optional[float] = None
        self._rate: Deque[Tuple[float, int]] = collections.deque(maxlen=20)
        self._threads = [threading.Thread(target=self._acquire, name="flatline-live-frames",
                                          daemon=True),
                         threading.Thread(target=self._present, name="flatline-live-overlay",
                                          daemon=True)]

    def start(self) -> None:
        for thread in self._threads:
            thread.start()

    def stop(self) -> None:
        self._stop.set()
        for thread in self._threads:
            thread.join(timeout=10)
        self.frames.close()
        self.gauge.close()
        self.extractor.close()

    # -- the threads ----------------------------------------------------------

    def _acquire(self) -> None:
        try:
            while not self._stop.is_set():
                got = self.frames.next()
                if got is None:
                    continue
                image, encoder = got
                if self._first_encoder is None:
                    self._first_encoder = encoder
                    self._next_cut = encoder + self.cut_every_mm
                if self.cut_every_mm > 0:
                    while encoder >= self._next_cut:
                        self.gauge.cut(self._next_cut)
                        self._next_cut += self.cut_every_mm
                self.gauge.push_frame(image, encoder)
                with self._lock:
                    self._frames += 1
                    # a copy only when the overlay thread asks for a frame
                    # (the simulator renders the next frame into the same
                    # array)
                    if self._want:
                        self._latest = (image.copy(), encoder, self._frames)
                        self._want = False
        except EOFError as exc:
            with self._lock:
                self._finished = str(exc)
        except Exception as exc:  # shown on the page: the view stays up
            with self._lock:
                self._error = f"acquisition stopped: {type(exc).__name__}: {exc}"

    def _present(self) -> None:
        shown = -1
        while not self._stop.is_set():
            started = time.monotonic()
            with self._lock:
                latest = self._latest
                self._want = True
            if latest is not None and latest[2] != shown:
                image, _, number = latest
                try:
                    rgb, info = render_overlay(image, self.frames.bits, self.extractor,
                                               self.calib)
                    overlay = png_bytes(rgb)
                    raw = png_bytes(_grey8(image, self.frames.bits))
                    with self._lock:
                        self._overlay, self._raw = overlay, raw
                        self._overlay_info = info
                        self._overlay_seq += 1
                        if self._first_overlay_s is None:
                            self._first_overlay_s = time.monotonic() - self._started
                    shown = number
                except Exception as exc:
                    with self._lock:
                        self._error = f"overlay: {type(exc).__name__}: {exc}"
            try:
                for sheet in self.gauge:
                    self._add_sheet(sheet)
            except flatline.FlatlineError as exc:
                with self._lock:
                    self._error = f"gauge: {exc}"
            self._stop.wait(max(0.0, OVERLAY_PERIOD_S - (time.monotonic() - started)))

    def _add_sheet(self, sheet: flatline.Sheet) -> None:
        if sheet.z is not None and sheet.rows > 0:
            picture, lo, hi = _height_map_png(sheet)
        else:
            picture, lo, hi = png_bytes(np.full((1, 1), 128, np.uint8)), math.nan, math.nan
        summary = _sheet_summary(sheet, (lo, hi))
        with self._lock:
            # A final sheet replaces its early answer (gauge_provisional_mm).
            for i, shown in enumerate(self._sheets):
                if shown["id"] == sheet.id:
                    self._sheets[i] = summary
                    self._sheet_png[sheet.id] = picture
                    return
            if len(self._sheets) == self._sheets.maxlen:
                self._sheet_png.pop(self._sheets[0]["id"], None)
            self._sheets.append(summary)
            self._sheet_png[sheet.id] = picture

    # -- what the page reads ---------------------------------------------------

    def state(self) -> Dict[str, Any]:
        now = time.monotonic()
        with self._lock:
            frames = self._frames
            self._rate.append((now, frames))
            t0, f0 = self._rate[0]
            state = {
                "source": self.frames.description,
                "uptime_s": now - self._started,
                "frames": frames,
                "frames_per_s": (frames - f0) / (now - t0) if now > t0 else 0.0,
                "overlay": {"seq": self._overlay_seq, "first_after_s": self._first_overlay_s,
                            **self._overlay_info},
                "source_counters": self.frames.counters(),
                "sheets": list(self._sheets)[::-1],
                "rules": self.rules_name,
                "error": self._error,
                "finished": self._finished,
            }
        state["gauge"] = self.gauge.counters()
        return _json_safe(state)

    def overlay_png(self) -> bytes:
        with self._lock:
            return self._overlay

    def raw_png(self) -> bytes:
        with self._lock:
            return self._raw

    def sheet_png(self, sheet_id: int) -> Optional[bytes]:
        with self._lock:
            return self._sheet_png.get(sheet_id)


def _json_safe(value: Any) -> Any:
    """NaN and infinities as null (JSON has none)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value


# ---------------------------------------------------------------------------
# The page and the server
# ---------------------------------------------------------------------------

PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>flatline live view</title>
<style>
body { font: 14px system-ui, sans-serif; margin: 12px; background: #f4f4f4; color: #222; }
h1 { font-size: 18px; margin: 0 0 4px; } h2 { font-size: 15px; margin: 12px 0 4px; }
.panel { background: #fff; border: 1px solid #ccc; padding: 8px; margin-bottom: 10px; }
#frame { width: 100%; image-rendering: pixelated; background: #000; min-height: 40px; }
table { border-collapse: collapse; } td, th { padding: 2px 8px; text-align: right; }
th { background: #eee; } td.l, th.l { text-align: left; }
.legend span { display: inline-block; width: 12px; height: 12px; margin: 0 4px 0 12px;
  vertical-align: middle; }
#counters { columns: 4 220px; } #counters div { display: flex; justify-content: space-between;
  padding: 1px 8px; break-inside: avoid; } #counters div:nth-child(odd) { background: #f6f6f6; }
#sheets { display: flex; flex-wrap: wrap; gap: 8px; }
.sheet { background: #fff; border: 1px solid #ccc; padding: 6px; width: 300px; }
.sheet img { width: 100%; height: 140px; image-rendering: pixelated; }
.sheet table { width: 100%; font-size: 12px; table-layout: fixed; }
.sheet td, .sheet th { padding: 1px 3px; overflow-wrap: anywhere; }
.sheet td.l, .sheet th.l { width: 45%; }
.pass { color: #060; font-weight: bold; } .fail { color: #b00; font-weight: bold; }
.error { color: #b00; } .muted { color: #777; }
</style></head>
<body data-overlay-seq="0" data-overlay-shown="0" data-sheets-shown="0">
<h1>flatline live view</h1>
<div id="source" class="muted"></div>
<div id="error" class="error"></div>
<div class="panel"><img id="frame" alt="the camera frame with the overlay">
<div class="legend">
<span style="background:#00ff00"></span>line 0
<span style="background:#00aaff"></span>line 1
<span style="background:#007800"></span>band 0 / <span style="background:#00508c"></span>band 1
<span style="background:#ff0000"></span>saturated
<span style="background:#ff9600"></span>strip edges</div>
<div class="muted" id="overlay-note"></div>
<table id="lasers"><thead><tr><th class="l">laser</th><th>band rows</th>
<th>columns with a line</th><th>saturated</th><th>line level</th><th>background</th>
<th>contrast</th><th>strip left, mm</th><th>strip right, mm</th></tr></thead>
<tbody></tbody></table></div>
<div class="panel"><h2>Counters</h2><div id="counters"></div></div>
<h2>Last sheets</h2><div id="sheets"></div>
<script>
"use strict";
const $ = (id) => document.getElementById(id);
const pct = (v) => v == null ? "&ndash;" : (100 * v).toFixed(1) + " %";
const mm = (v) => v == null ? "open" : v.toFixed(1);
const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({"&": "&amp;", "<": "&lt;",
  ">": "&gt;", '"': "&quot;"}[c]));
let shownSeq = 0, loadingSeq = 0, sheetKey = "";
$("frame").addEventListener("load", () => {
  if (!document.body.dataset.overlayFirstMs)  // ms after the page began to load
    document.body.dataset.overlayFirstMs = String(Math.round(performance.now()));
  document.body.dataset.overlaySeq = String(loadingSeq);
  document.body.dataset.overlayShown = String(Number(document.body.dataset.overlayShown) + 1);
});
function zoneBars(zones) {
  const w = 288, h = 60, n = zones.length || 1, bw = w / n;
  const top = Math.max(1, ...zones.map((z) => z.i_units || 0));
  let s = `<svg width="${w}" height="${h + 14}" role="img" aria-label="zone I-Units">`;
  zones.forEach((z, i) => {
    const v = z.i_units == null ? 0 : z.i_units, bh = h * v / top;
    s += `<rect x="${i * bw + 1}" y="${h - bh}" width="${Math.max(bw - 2, 1)}" height="${bh}"`
       + ` fill="${z.i_units == null ? "#bbb" : "#4a6fb5"}"><title>zone ${i + 1}: `
       + `${z.i_units == null ? "no data" : v.toFixed(1) + " I-Units"}</title></rect>`;
  });
  s += `<text x="0" y="${h + 12}" font-size="10">drive side</text>`;
  s += `<text x="${w}" y="${h + 12}" font-size="10" text-anchor="end">operator side `
     + `(max ${top.toFixed(1)} I)</text></svg>`;
  return s;
}
function sheetCard(s) {
  // The sheet's own verdict: a sheet no rule could judge is never shown
  // as passed; an early answer says so until its final replaces it.
  const early = s.provisional ? ' <span class="muted">(provisional)</span>' : "";
  const verdict = (s.rules === 0 ? '<span class="muted">no rules</span>'
    : s.state === "fail" ? `<span class="fail">FAIL (${s.failed} of ${s.rules} rules)</span>`
    : s.state === "pass" ? '<span class="pass">PASS</span>'
    : '<span class="muted">NOT JUDGED</span>') + early;
  const rules = s.verdict.map((r) => `<tr><td class="l">${esc(r.rule)}</td>`
    + `<td class="${r.state === "fail" ? "fail" : ""}">${esc(r.state.replace("_", " "))}</td>`
    + `<td>${r.worst == null ? "&ndash;" : r.worst.toFixed(2)}</td>`
    + `<td>${r.limit == null ? "&ndash;" : r.limit.toFixed(2)}</td></tr>`).join("");
  const scale = s.scale_mm[0] == null ? "" :
    `<div class="muted">blue ${s.scale_mm[0].toFixed(2)} mm .. red ${s.scale_mm[1].toFixed(2)} mm</div>`;
  return `<div class="sheet" data-sheet="${s.id}"><b>sheet ${s.id}</b> (coil ${s.coil}, `
    + `#${s.index}), ${(s.length_mm / 1000).toFixed(2)} m, ${esc(s.shape)}, `
    + `max ${s.max_i_units == null ? "&ndash;" : s.max_i_units.toFixed(1)} I-Units `
    + `<div>${verdict}</div><img src="/sheet/${s.id}.png" alt="height map of sheet ${s.id}">`
    + scale + zoneBars(s.zones)
    + (rules ? `<table><tr><th class="l">rule</th><th>result</th><th>worst</th>`
       + `<th>limit</th></tr>${rules}</table>` : "") + "</div>";
}
async function poll() {
  try {
    const st = await (await fetch("/state.json", {cache: "no-store"})).json();
    $("source").textContent = st.source + " \\u2014 up " + st.uptime_s.toFixed(0) + " s";
    $("error").textContent = st.error || st.overlay.error ||
      (st.finished ? st.finished + ": the view keeps the last picture" : "");
    if (st.overlay.seq > shownSeq) {
      shownSeq = loadingSeq = st.overlay.seq;
      $("frame").src = "/overlay.png?seq=" + st.overlay.seq;
      $("lasers").tBodies[0].innerHTML = (st.overlay.lasers || []).map((l) =>
        `<tr><td class="l">${l.laser}</td><td>${l.band[0]}..${l.band[1]}</td>`
        + `<td>${l.peaks}</td><td>${l.saturated} (${pct(l.saturated_fraction)})</td>`
        + `<td>${pct(l.line_level)}</td><td>${pct(l.background_level)}</td>`
        + `<td>${pct(l.contrast)}</td><td>${mm(l.strip_left_mm)}</td>`
        + `<td>${mm(l.strip_right_mm)}</td></tr>`).join("");
      $("overlay-note").textContent = "frame " + st.frames + ", "
        + st.overlay.saturated_pixels + " saturated pixels";
    }
    const rows = [["frames", st.frames], ["frames/s", st.frames_per_s.toFixed(1)]];
    for (const [k, v] of Object.entries(st.source_counters)) rows.push(["source " + k, v]);
    for (const [k, v] of Object.entries(st.gauge)) rows.push(["gauge " + k, v]);
    $("counters").innerHTML = rows.map(([k, v]) =>
      `<div><span>${esc(k)}</span><span>${esc(v)}</span></div>`).join("");
    const key = st.sheets.map((s) => s.id).join(",");
    if (key !== sheetKey) {
      sheetKey = key;
      $("sheets").innerHTML = st.sheets.map(sheetCard).join("")
        || '<span class="muted">no sheet finished yet</span>';
      document.body.dataset.sheetsShown = String(st.sheets.length);
    }
  } catch (e) {
    $("error").textContent = "the live view does not answer: " + e;
  }
  setTimeout(poll, 250);
}
poll();
</script></body></html>
"""


def _handler(view: LiveView) -> type:
    class Handler(BaseHTTPRequestHandler):
        server_version = "flatline-live"

        def log_message(self, format: str, *args: Any) -> None:  # noqa: A002
            pass  # quiet: the page polls several times a second

        def _send(self, status: int, kind: str, body: bytes) -> None:
            self.send_response(status)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")
            # nothing from elsewhere: the page's own script and pictures only
            self.send_header("Content-Security-Policy",
                             "default-src 'self'; script-src 'unsafe-inline'; "
                             "style-src 'unsafe-inline'; img-src 'self'")
            self.end_headers()
            self.wfile.write(body)

        def do_GET(self) -> None:  # noqa: N802
            path = self.path.split("?", 1)[0]
            if path in ("/", "/index.html"):
                self._send(200, "text/html; charset=utf-8", PAGE.encode("utf-8"))
            elif path == "/state.json":
                self._send(200, "application/json",
                           json.dumps(view.state(), allow_nan=False).encode("utf-8"))
            elif path in ("/overlay.png", "/raw.png"):
                body = view.overlay_png() if path == "/overlay.png" else view.raw_png()
                if body:
                    self._send(200, "image/png", body)
                else:
                    self._send(503, "text/plain", b"no frame yet")
            else:
                m = re.fullmatch(r"/sheet/(\d{1,12})\.png", path)
                body = view.sheet_png(int(m.group(1))) if m else None
                if body:
                    self._send(200, "image/png", body)
                else:
                    self._send(404, "text/plain", b"not found")

    return Handler


# ---------------------------------------------------------------------------
# The command
# ---------------------------------------------------------------------------

def _arguments(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="flatline-live",
        description="A live view of the gauge in the browser: the frame with the extracted "
                    "lines, bands, saturation and strip edges, per-laser contrast and "
                    "saturation, counters, the last sheets' height maps, zone bars and "
                    "verdicts.")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--simulate", action="store_true",
                     help="the simulated line (the default without --camera or --images)")
    src.add_argument("--camera", metavar="CAMERA",
                     help="u3v, u3v:SERIAL, gige:ADDRESS|SERIAL, or an IPv4 address")
    src.add_argument("--images", metavar="DIR", help="a folder of PNG/TIFF frames, in name order")
    p.add_argument("--calib", metavar="FILE",
                   help="the sensor's calibration (needed with --camera and --images; the "
                        "simulator uses the reference sensor's 2048 x 256 window without it)")
    p.add_argument("--rules", metavar="FILE",
                   help="a tolerance rule file: each sheet's verdict (the simulator takes the "
                        "example rules without it)")
    p.add_argument("--thickness", type=float, default=3.0, metavar="MM",
                   help="strip thickness for the rules' bands (default 3)")
    p.add_argument("--width", type=float, default=0.0, metavar="MM",
                   help="nominal strip width for the rules' bands (default: measured)")
    p.add_argument("--sheet-length", type=float, default=3000.0, metavar="MM",
                   help="simulator: a shear cut every this many mm (default 3000); a camera "
                        "without cuts ends sheets at gauge_max_sheet_length")
    p.add_argument("--frame-spacing", type=float, default=3.0, metavar="MM",
                   help="simulator: strip travel between frames (default 3)")
    p.add_argument("--strip-width", type=float, default=1500.0, metavar="MM",
                   help="simulator: the strip's width (default 1500)")
    p.add_argument("--seed", type=int, default=1, help="simulator: noise seed")
    p.add_argument("--lag-knots", type=int, default=0, metavar="N",
                   help="the reconstructor's lag, knots (default: from the library's "
                        "latency_mm, 2000 mm: 15 knots); fewer show sheets sooner, less "
                        "smoothed")
    p.add_argument("--listen", default="127.0.0.1", metavar="ADDRESS",
                   help="the address to serve on (default 127.0.0.1: this computer only; "
                        "0.0.0.0 for every interface, a network you trust)")
    p.add_argument("--port", type=int, default=8090,
                   help="the port (default 8090; 0 picks a free one)")
    p.add_argument("--seconds", type=float, default=0.0,
                   help="stop after this many seconds (default: run until Ctrl-C)")
    args = p.parse_args(argv)
    for name in ("thickness", "sheet_length", "frame_spacing", "strip_width"):
        v = getattr(args, name)
        if not (math.isfinite(v) and v > 0):
            p.error(f"--{name.replace('_', '-')} must be a positive number, not {v}")
    if not (0 <= args.port <= 65535):
        p.error(f"--port must be 0 .. 65535, not {args.port}")
    if (args.camera or args.images) and not args.calib:
        p.error("--camera and --images need --calib: the lines are found and measured through "
                "the sensor's calibration")
    return args


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = _arguments(argv)
    try:
        if args.calib:
            calib = flatline.Calibration.load(args.calib)
        else:
            calib = flatline.Calibration.reference(first_row=892, rows=256,
                                                   first_x_mm=-1000.0, pitch_mm=5.0, fibers=401)
        rules = None
        rules_name = ""
        if args.rules:
            rules = flatline.ToleranceRules.load(args.rules)
            rules_name = args.rules
        elif not (args.camera or args.images):
            example = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                   "example_rules.json")
            if os.path.isfile(example):
                rules = flatline.ToleranceRules.load(example)
                rules_name = "example rules (invented limits)"
        if args.camera:
            frames: Any = _FromSource(_open_camera(args.camera), f"camera {args.camera}")
        elif args.images:
            frames = _FromSource(flatline.Source.images(args.images), f"images in {args.images}")
        else:
            frames = _Simulated(calib, args)
    except (flatline.FlatlineError, OSError, ValueError) as exc:
        print(f"flatline-live: {exc}", file=sys.stderr)
        return 1
    gauge_options: Dict[str, float] = {}
    if args.lag_knots:
        gauge_options["lag_knots"] = args.lag_knots
    if not (args.camera or args.images):
        gauge_options["gauge_frame_spacing"] = 0.8 * args.frame_spacing
    cut = args.sheet_length if not (args.camera or args.images) else 0.0
    try:
        view = LiveView(frames, calib, rules=rules, thickness_mm=args.thickness,
                        width_mm=args.width, cut_every_mm=cut, gauge_options=gauge_options)
    except (flatline.FlatlineError, ValueError) as exc:
        frames.close()
        print(f"flatline-live: {exc}", file=sys.stderr)
        return 1
    view.rules_name = rules_name
    try:
        server = ThreadingHTTPServer((args.listen, args.port), _handler(view))
    except OSError as exc:
        view.stop()
        print(f"flatline-live: cannot listen on {args.listen}:{args.port}: {exc}",
              file=sys.stderr)
        return 1
    server.daemon_threads = True
    host, port = server.server_address[:2]
    view.start()
    shown_host = host if ":" not in str(host) else f"[{host}]"
    print(f"flatline-live: {frames.description}", flush=True)
    print(f"flatline-live: serving http://{shown_host}:{port}/ (Ctrl-C stops)", flush=True)
    if args.listen not in ("127.0.0.1", "localhost", "::1"):
        print(f"flatline-live: listening on {args.listen}: anyone who reaches this port sees "
              f"the page", flush=True)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        if args.seconds > 0:
            time.sleep(args.seconds)
        else:
            while True:
                time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        server.shutdown()
        server.server_close()
        view.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
