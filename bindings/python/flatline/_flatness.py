# SPDX-License-Identifier: Apache-2.0
"""Flatness metrics (flatline/flatness.h): I-Units per fiber and per zone,
the largest wave, the shape class, bow and crossbow, from reconstructed
rows."""

from __future__ import annotations

import enum
import threading
from dataclasses import dataclass
from typing import Any, Dict, Iterator, Optional, Tuple, Union

import numpy as np

from . import capi as _capi
from ._arrays import as_float64, check_shape
from ._calib import Calibration
from ._errors import StateError
from ._options import OptionValue, make_options, options_doc, prefixed_options

__all__ = [
    "FIBER_NO_DATA",
    "FIBER_NO_WAVE",
    "FIBER_PARTIAL",
    "ZONE_NO_DATA",
    "WINDOW_SHORT",
    "WINDOW_NO_VALID_FIBER",
    "WINDOW_NO_BOW",
    "WINDOW_NO_CROSSBOW",
    "FIBER_OFF_STRIP",
    "ZONE_OFF_STRIP",
    "WINDOW_ON_STRIP",
    "Shape",
    "ShapeComponent",
    "FiberResults",
    "ZoneResults",
    "ShapeResult",
    "WindowInfo",
    "FlatnessResult",
    "StripWindow",
    "Flatness",
    "flatness_options",
    "i_units",
]

#: Less than flat_min_coverage of the window usable: the fiber's values are NaN.
FIBER_NO_DATA: int = _capi.FLT_FIBER_NO_DATA
#: No complete wave above flat_wave_hysteresis: wave height, period, steepness NaN.
FIBER_NO_WAVE: int = _capi.FLT_FIBER_NO_WAVE
#: Some rows unusable; the arc length is scaled from the covered part.
FIBER_PARTIAL: int = _capi.FLT_FIBER_PARTIAL
#: No valid fiber in the zone: its I-Units are NaN.
ZONE_NO_DATA: int = _capi.FLT_ZONE_NO_DATA
#: The window is shorter than flat_min_length: no wave, shape undetermined.
WINDOW_SHORT: int = _capi.FLT_WINDOW_SHORT
#: No fiber is valid: every value is NaN and flagged.
WINDOW_NO_VALID_FIBER: int = _capi.FLT_WINDOW_NO_VALID_FIBER
#: No valid fiber has 3 usable rows: bow_mm is NaN.
WINDOW_NO_BOW: int = _capi.FLT_WINDOW_NO_BOW
#: Fewer than 3 valid fibers: crossbow_mm is NaN.
WINDOW_NO_CROSSBOW: int = _capi.FLT_WINDOW_NO_CROSSBOW
#: The result slot lies beyond the strip's edges (zones on the strip);
#: FIBER_NO_DATA is set too.
FIBER_OFF_STRIP: int = _capi.FLT_FIBER_OFF_STRIP
#: The zone lies beyond the strip's zones (a strip narrower than the grid);
#: ZONE_NO_DATA is set too.
ZONE_OFF_STRIP: int = _capi.FLT_ZONE_OFF_STRIP
#: The strip's edges were known in the window: fibers and zones lie on the
#: strip (strip coordinates), not on the sensor's fiber grid.
WINDOW_ON_STRIP: int = _capi.FLT_WINDOW_ON_STRIP


class Shape(enum.IntEnum):
    """The shape class of a window (flt_shape), from its zone I-Unit
    profile; ``str(shape)``/``.label`` is the library's name
    (flt_shape_string), e.g. "centre buckle"."""

    FLAT = _capi.FLT_SHAPE_FLAT
    CENTRE_BUCKLE = _capi.FLT_SHAPE_CENTRE_BUCKLE
    WAVY_EDGE_LEFT = _capi.FLT_SHAPE_WAVY_EDGE_LEFT
    WAVY_EDGE_RIGHT = _capi.FLT_SHAPE_WAVY_EDGE_RIGHT
    #: WAVY_EDGE_LEFT by the operator's name (flat_drive_side says where it is)
    WAVY_EDGE_DRIVE_SIDE = _capi.FLT_SHAPE_WAVY_EDGE_DRIVE_SIDE
    #: WAVY_EDGE_RIGHT by the operator's name
    WAVY_EDGE_OPERATOR_SIDE = _capi.FLT_SHAPE_WAVY_EDGE_OPERATOR_SIDE
    WAVY_EDGE_BOTH = _capi.FLT_SHAPE_WAVY_EDGE_BOTH
    QUARTER_BUCKLE = _capi.FLT_SHAPE_QUARTER_BUCKLE
    MIX = _capi.FLT_SHAPE_MIX
    UNDETERMINED = _capi.FLT_SHAPE_UNDETERMINED
    #: not judged: the gauge's sheet is incomplete (SheetFlag.INCOMPLETE)
    NOT_JUDGED = _capi.FLT_SHAPE_NOT_JUDGED

    @property
    def label(self) -> str:
        """The library's lower-case English name (flt_shape_string)."""
        return _capi.flt_shape_string(int(self))

    def __str__(self) -> str:
        return self.label


class ShapeComponent(enum.IntFlag):
    """Components of a shape (FLT_SHAPE_HAS_* bits). BOW and CROSSBOW are set
    when |bow_mm| >= flat_bow_limit and |crossbow_mm| >= flat_crossbow_limit."""

    # print() and f-strings show the names (HEAD|FLUSHED), as repr does,
    # not the number that IntFlag's str gives since Python 3.11.
    __str__ = enum.Flag.__str__
    __format__ = enum.Flag.__format__

    NONE = 0
    CENTRE = _capi.FLT_SHAPE_HAS_CENTRE
    EDGE_LEFT = _capi.FLT_SHAPE_HAS_EDGE_LEFT
    EDGE_RIGHT = _capi.FLT_SHAPE_HAS_EDGE_RIGHT
    QUARTER = _capi.FLT_SHAPE_HAS_QUARTER
    BOW = _capi.FLT_SHAPE_HAS_BOW
    CROSSBOW = _capi.FLT_SHAPE_HAS_CROSSBOW


@dataclass(frozen=True)
class FiberResults:
    """Per-fiber results of one window, (K,) arrays. NaN only where the
    matching flag (FIBER_NO_DATA, FIBER_NO_WAVE) says so."""

    x: np.ndarray  #: (K,) fiber positions across the width, mm
    arc_length: np.ndarray  #: (K,) arc length of z(s) over the window, mm
    i_units: np.ndarray  #: (K,) (l - l_ref) / l_ref * 1e5, I-Units
    wave_height: np.ndarray  #: (K,) peak-to-peak height of the largest wave, mm
    wave_period: np.ndarray  #: (K,) its period, mm
    steepness_percent: np.ndarray  #: (K,) 100 * height / period, %
    flags: np.ndarray  #: (K,) uint8 FIBER_* bits


@dataclass(frozen=True)
class ZoneResults:
    """The zone profile of one window, (zones,) arrays: zone j covers
    [left_x[j], left_x[j] + flat_zone_width) mm across the width."""

    left_x: np.ndarray  #: (zones,) left edge, mm
    centre_x: np.ndarray  #: (zones,) centre, mm
    fiber_count: np.ndarray  #: (zones,) int64 fibers in the zone
    i_units: np.ndarray  #: (zones,) mean I-Units of the zone's valid fibers; NaN with ZONE_NO_DATA
    flags: np.ndarray  #: (zones,) uint8 ZONE_* bits


@dataclass(frozen=True)
class ShapeResult:
    """The shape of one window."""

    shape: Shape  #: the class
    name: str  #: the library's name of the class, e.g. "wavy edge both"
    confidence: float  #: in [0, 1]
    components: ShapeComponent  #: FLT_SHAPE_HAS_* bits
    bow_mm: float  #: coil-set sagitta over the window, mm (> 0: ends higher); NaN with WINDOW_NO_BOW
    crossbow_mm: float  #: transverse sagitta over the width, mm (> 0: edges higher); NaN with WINDOW_NO_CROSSBOW


@dataclass(frozen=True)
class WindowInfo:
    """Which rows one window covered."""

    s_first: float  #: s of its first row, mm
    s_last: float  #: s of its last row, mm
    rows: int  #: its row count
    flags: int  #: WINDOW_* bits
    index: int  #: sequence number, 1 for the first window since create


@dataclass(frozen=True)
class StripWindow:
    """Where one window's results lie on the strip. With WINDOW_ON_STRIP
    (the strip's edges were known) result fiber k is the strip coordinate
    ``fiber_strip_x[k]`` (mm from the strip's centre line towards the
    operator side), not sensor fiber k, and zones are laid on the strip;
    without it, on the fiber grid (strip coordinates from its centre)."""

    on_strip: bool  #: WINDOW_ON_STRIP was set
    width_mm: Tuple[float, float, float]  #: the strip's width (mean, min, max) over the window
    centre_mm: Tuple[float, float, float]  #: its centre line's sensor x (mean, min, max)
    fiber_strip_x: np.ndarray  #: (K,) each result fiber's strip coordinate, mm
    fiber_sensor_x: np.ndarray  #: (K,) its sensor x at the window's mean position, mm
    zone_strip_centre: np.ndarray  #: (zones,) zone centres in strip coordinates; NaN with ZONE_OFF_STRIP
    zone_sensor_centre: np.ndarray  #: (zones,) zone centres in sensor x, mm
    zone_width: np.ndarray  #: (zones,) zone widths, mm (0 off the strip)
    zone_fiber_count: np.ndarray  #: (zones,) int64 result fibers in each zone


@dataclass(frozen=True)
class FlatnessResult:
    """Everything about one evaluated window (copies: later windows do not
    change it)."""

    window: WindowInfo
    fibers: FiberResults
    zones: ZoneResults
    shape: ShapeResult
    #: where the results lie on the strip (always filled by :class:`Flatness`)
    strip: Optional[StripWindow] = None


def flatness_options() -> Dict[str, float]:
    """The flatness options (flat_*) with their C defaults."""
    return {name: info.default for name, info in prefixed_options("flat_").items()}


_NO_FLAGS = np.zeros((1, 1), dtype=np.uint8)  # numpy.i has no optional arrays


def _edges(function: str, rows: int, left_mm: Any,
           right_mm: Any) -> Optional[Tuple[np.ndarray, np.ndarray]]:
    """The strip's edges per row as two (rows,) float64 arrays (NaN:
    unknown), or None when neither is given."""
    if left_mm is None and right_mm is None:
        return None
    out = []
    for name, value in (("left_mm", left_mm), ("right_mm", right_mm)):
        if value is None:
            out.append(np.full(rows, np.nan))
            continue
        array = as_float64(function, name, value, 1)
        check_shape(function, name, array, (rows,), "z.shape[0]")
        out.append(array)
    return out[0], out[1]


def _rows(function: str, fibers: int, s: Any, z: Any,
          flags: Any) -> Tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    z = as_float64(function, "z", z, 2)
    rows = z.shape[0]
    if z.shape[1] != fibers:
        raise ValueError(f"{function}() argument 'z' has shape {z.shape}, but the "
                         f"Flatness has {fibers} fibers")
    s = as_float64(function, "s", s, 1)
    check_shape(function, "s", s, (rows,), "z.shape[0]")
    if flags is None:
        return s, z, _NO_FLAGS, 0
    array = np.asanyarray(flags)
    if array.dtype == np.bool_ or array.dtype.kind not in "iu":
        raise TypeError(f"{function}() argument 'flags' must be an integer array of "
                        f"FLAG_* bits (the reconstructor's uint8 flags), got dtype "
                        f"{array.dtype}")
    if array.ndim != 2:
        raise ValueError(f"{function}() argument 'flags' must have 2 dimensions, got "
                         f"shape {array.shape}")
    check_shape(function, "flags", array, z.shape, "z.shape")
    if array.dtype != np.uint8:
        if array.size and (array.min() < 0 or array.max() > 255):
            raise ValueError(f"{function}() argument 'flags' holds values outside "
                             f"[0, 255]")
        array = array.astype(np.uint8)
    return s, z, np.require(array, requirements=("C", "A")), 1


class Flatness:
    """Flatness metrics for a fixed fiber grid.

    Args:
        fiber_x: (K,) fiber positions across the width, mm (finite, strictly
            increasing; copied), or a finished :class:`Calibration` whose
            fiber grid is used.
        **options: flatness options by their C name (see below).

    Two ways to use it (see flatline/flatness.h):

    * :meth:`evaluate` (s, z, flags) evaluates one window from the caller's
      rows, e.g. a whole sheet from :func:`reconstruct`, and returns its
      :class:`FlatnessResult`. Too short a sheet or one without a valid fiber
      raises InvalidArgumentError and keeps the previous results.
    * Streaming: :meth:`push` takes rows until a window (the last
      flat_window_length mm, every flat_update_interval mm) completes and
      returns ``(consumed, evaluated)``: push the rest again after reading
      :meth:`result`. :meth:`windows` does that loop and yields each
      window's :class:`FlatnessResult`. :meth:`finish` evaluates the rows of
      the last, partial window (the end of a sheet) and :meth:`reset` drops
      pending rows.

    z is reconstructed heights (N, K) mm (NaN allowed where flagged), s the
    rows' material positions (N,) mm, flags the reconstructor's (N, K) uint8
    FLAG_* bits or None. One Flatness serialises its calls; separate ones run
    in parallel (the GIL is released in evaluate and push).

    Options:
{options}
    """

    def __init__(self, fiber_x: Union[Any, Calibration], **options: OptionValue) -> None:
        fn = "Flatness"
        bag = make_options(fn, options, prefixes=("flat_",))
        self._lock = threading.Lock()
        if isinstance(fiber_x, Calibration):
            calib = fiber_x
            with calib._reading():
                handle = _capi.flt_flatness_create_from_calib(calib._live(), bag)
            x = np.array(calib.fiber_x, dtype=np.float64)
        else:
            x = np.array(as_float64(fn, "fiber_x", fiber_x, 1))
            handle = _capi.flt_py_flatness_create(x, bag)
        self._handle: Optional[_capi.flt_flatness] = handle
        self._fibers = int(_capi.flt_flatness_fibers(handle))
        self._zones = int(_capi.flt_flatness_zones(handle))
        self._x = x
        self._x.flags.writeable = False
        left = np.empty(self._zones)
        centre = np.empty(self._zones)
        count = np.empty(self._zones)
        handle.zone_layout_into(left, centre, count)
        self._layout = (left, centre, count.astype(np.int64))
        for array in self._layout:
            array.flags.writeable = False

    # -- lifetime -------------------------------------------------------------------

    def close(self) -> None:
        """Frees the C buffers now, even while a traceback or another object
        still refers to this Flatness. Idempotent; later calls raise
        StateError."""
        with self._lock:
            handle, self._handle = self._handle, None
            _capi.flt_py_release(handle)

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._handle is None

    def __enter__(self) -> "Flatness":
        self._live()
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def _live(self) -> _capi.flt_flatness:
        handle = self._handle
        if handle is None:
            raise StateError("the Flatness is closed")
        return handle

    def __repr__(self) -> str:
        if getattr(self, "_handle", None) is None:
            return "<flatline.Flatness closed>"
        return f"<flatline.Flatness fibers={self._fibers} zones={self._zones}>"

    # -- description ---------------------------------------------------------------

    @property
    def fibers(self) -> int:
        """The number of fibers K."""
        return self._fibers

    @property
    def zones(self) -> int:
        """The number of zones across the width."""
        return self._zones

    @property
    def fiber_x(self) -> np.ndarray:
        """The (K,) fiber positions, mm (read-only)."""
        return self._x

    @property
    def zone_left_x(self) -> np.ndarray:
        """(zones,) left edge of each zone, mm."""
        return self._layout[0]

    @property
    def zone_centre_x(self) -> np.ndarray:
        """(zones,) centre of each zone, mm."""
        return self._layout[1]

    @property
    def zone_fiber_count(self) -> np.ndarray:
        """(zones,) number of fibers in each zone."""
        return self._layout[2]

    # -- evaluation ----------------------------------------------------------------

    def evaluate(self, s: Any, z: Any, flags: Any = None, left_mm: Any = None,
                 right_mm: Any = None) -> FlatnessResult:
        """Evaluates one window from s (N,) mm, z (N, K) mm and flags (N, K)
        uint8 FLAG_* bits or None; returns its :class:`FlatnessResult`.
        Independent of the streaming state.

        left_mm, right_mm: the strip's edges per row (N,) in sensor x, mm
        (NaN where unknown; :meth:`Extractor.strip` with laser 2 gives
        them), or None. Where the edges are known (given, or taken from the
        flags' FLAG_OFF_STRIP bits), the window is measured on the strip:
        see :class:`StripWindow`."""
        fn = "evaluate"
        s, z, mask, flagged = _rows(fn, self._fibers, s, z, flags)
        edges = _edges(fn, len(s), left_mm, right_mm)
        with self._lock:
            handle = self._live()
            if edges is None:
                handle.evaluate_rows(s, z, mask, flagged)
            else:
                handle.evaluate_strip_rows(s, z, mask, flagged, edges[0], edges[1])
            return self._result(handle)

    def push(self, s: Any, z: Any, flags: Any = None, left_mm: Any = None,
             right_mm: Any = None) -> Tuple[int, bool]:
        """Streams rows (s continues to increase across calls) until a window
        completes. Returns ``(consumed, evaluated)``: the rows taken (all
        unless a window completed first) and whether a window was evaluated
        (read it with :meth:`result`, then push ``s[consumed:]`` etc. again).
        BufferFullError when a window would exceed flat_row_capacity rows.
        left_mm, right_mm: the strip's edges per row, as in :meth:`evaluate`."""
        fn = "push"
        s, z, mask, flagged = _rows(fn, self._fibers, s, z, flags)
        edges = _edges(fn, len(s), left_mm, right_mm)
        with self._lock:
            if edges is None:
                consumed, evaluated = self._live().push_rows(s, z, mask, flagged)
            else:
                consumed, evaluated = self._live().push_strip_rows(s, z, mask, flagged, edges[0],
                                                                   edges[1])
        return int(consumed), bool(evaluated)

    def windows(self, s: Any, z: Any, flags: Any = None, left_mm: Any = None,
                right_mm: Any = None) -> Iterator[FlatnessResult]:
        """Pushes all the rows, yielding the :class:`FlatnessResult` of every
        window they complete (in order). Does not :meth:`finish`.
        left_mm, right_mm: the strip's edges per row, as in :meth:`evaluate`."""
        fn = "windows"
        s, z, mask, flagged = _rows(fn, self._fibers, s, z, flags)
        edges = _edges(fn, len(s), left_mm, right_mm)
        start = 0
        rows = len(s)
        while start < rows:
            part = (s[start:], z[start:], mask[start:] if flagged else mask)
            with self._lock:
                handle = self._live()
                if edges is None:
                    consumed, evaluated = handle.push_rows(*part, flagged)
                else:
                    consumed, evaluated = handle.push_strip_rows(
                        *part, flagged, edges[0][start:], edges[1][start:])
                result = self._result(handle) if evaluated else None
            start += int(consumed)
            if result is not None:
                yield result
            elif consumed == 0:  # cannot happen without a window; never spin
                break

    def finish(self) -> Optional[FlatnessResult]:
        """Ends the sheet: evaluates the rows since the current window's
        start as one last window and returns its result (flagged
        WINDOW_SHORT if shorter than flat_min_length), or None when fewer
        than 2 rows were pending. The next push starts a new window grid."""
        with self._lock:
            handle = self._live()
            evaluated = _capi.flt_flatness_finish(handle)
            return self._result(handle) if evaluated else None

    def reset(self) -> None:
        """Drops the pending rows and restarts the window grid; the last
        results stay readable."""
        with self._lock:
            _capi.flt_flatness_reset(self._live())

    def result(self) -> FlatnessResult:
        """The last evaluated window's :class:`FlatnessResult` (StateError
        before the first window)."""
        with self._lock:
            return self._result(self._live())

    def _result(self, handle: _capi.flt_flatness) -> FlatnessResult:
        k, zones = self._fibers, self._zones
        window = np.empty(5)
        handle.window_into(window)
        arc, iu, height, period, steep = (np.empty(k) for _ in range(5))
        fiber_flags = np.empty(k, dtype=np.uint8)
        handle.fiber_results_into(arc, iu, height, period, steep, fiber_flags)
        zone_iu = np.empty(zones)
        zone_flags = np.empty(zones, dtype=np.uint8)
        handle.zone_results_into(zone_iu, zone_flags)
        shape = np.empty(5)
        handle.shape_into(shape)
        kind = Shape(int(shape[0]))
        strip = np.empty(6)
        handle.strip_into(strip)
        fiber_strip, fiber_sensor = np.empty(k), np.empty(k)
        handle.fiber_positions_into(fiber_strip, fiber_sensor)
        zone_strip, zone_sensor, zone_width, zone_fibers = (np.empty(zones) for _ in range(4))
        handle.zone_positions_into(zone_strip, zone_sensor, zone_width, zone_fibers)
        on_strip = StripWindow(bool(int(window[3]) & WINDOW_ON_STRIP),
                               (float(strip[0]), float(strip[1]), float(strip[2])),
                               (float(strip[3]), float(strip[4]), float(strip[5])),
                               fiber_strip, fiber_sensor, zone_strip, zone_sensor, zone_width,
                               zone_fibers.astype(np.int64))
        return FlatnessResult(
            WindowInfo(float(window[0]), float(window[1]), int(window[2]), int(window[3]),
                       int(window[4])),
            FiberResults(self._x, arc, iu, height, period, steep, fiber_flags),
            ZoneResults(self._layout[0], self._layout[1], self._layout[2], zone_iu,
                        zone_flags),
            ShapeResult(kind, kind.label, float(shape[1]), ShapeComponent(int(shape[2])),
                        float(shape[3]), float(shape[4])),
            on_strip,
        )


def i_units(z: Any, s: Any, fiber_x: Any = None, flags: Any = None,
            **options: OptionValue) -> FlatnessResult:
    """Flatness of one whole sheet: a :class:`Flatness` over fiber_x
    evaluated once on all rows. Returns the :class:`FlatnessResult`; the
    per-fiber I-Units are ``result.fibers.i_units`` (K,), the zone profile
    ``result.zones.i_units`` and the class ``result.shape``.

    Args:
        z: (N, K) reconstructed heights, mm.
        s: (N,) material positions, mm, strictly increasing.
        fiber_x: (K,) fiber positions, mm; None: fibers 1 mm apart from
            x = 0 (per-fiber I-Units and waves do not depend on x; zones,
            shape and crossbow do).
        flags: (N, K) reconstructor flags or None.
        **options: flatness options (flat_*).

    For a sine of peak-to-peak height H and period P along every fiber,
    I = 2.467 (H/P)^2 1e5 for small H/P (relative to the shortest fiber,
    flat_reference = 0: give one flat fiber, or compare fibers).
    """
    fn = "i_units"
    z_arr = as_float64(fn, "z", z, 2)
    if fiber_x is None:
        fiber_x = np.arange(z_arr.shape[1], dtype=np.float64)
    with Flatness(fiber_x, **options) as flatness:
        return flatness.evaluate(s, z_arr, flags)


def _document_options() -> None:
    text = options_doc(flatness_options())
    if Flatness.__doc__:
        Flatness.__doc__ = Flatness.__doc__.replace("{options}", text)


_document_options()
