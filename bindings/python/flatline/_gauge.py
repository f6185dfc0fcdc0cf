# SPDX-License-Identifier: Apache-2.0
"""The gauge (flatline/gauge.h): one handle that runs a line. Camera frames
(or profile rows) and the shear's cuts go in, measured sheets come out."""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import Any, Dict, Iterator, Optional, Tuple, Union

import numpy as np

from . import _tables
from . import capi as _capi
from ._arrays import as_float64, as_mask, as_real
from . import _log
from ._calib import Calibration
from ._errors import FlatlineError, NotFoundError, StateError, TimeoutError
from ._flatness import FiberResults, Shape, ShapeComponent
from ._options import OptionValue, make_options, options_doc, prefixed_options
from ._pixels import PixelFormat, check_one_channel
from ._record import Archive, CoilInfo, Recorder
from ._source import Source
from ._verdict import RuleResult, ToleranceRules, VerdictState, _results, _rule_list

__all__ = [
    "SheetNote",
    "SheetFlag",
    "SheetZones",
    "Sheet",
    "RuleStats",
    "CoilStats",
    "Gauge",
    "gauge_options",
]


class SheetFlag(enum.IntFlag):
    """How a sheet began and ended, and which of its values are NaN
    (FLT_SHEET_FLAG_*)."""

    # print() and f-strings show the names (HEAD|FLUSHED), as repr does,
    # not the number that IntFlag's str gives since Python 3.11.
    __str__ = enum.Flag.__str__
    __format__ = enum.Flag.__format__

    NONE = 0
    HEAD = _capi.FLT_SHEET_FLAG_HEAD  #: starts at its strip's head, not a cut
    TAIL = _capi.FLT_SHEET_FLAG_TAIL  #: ends at its strip's tail
    FLUSHED = _capi.FLT_SHEET_FLAG_FLUSHED  #: ended by flush() (end of input)
    SPLIT = _capi.FLT_SHEET_FLAG_SPLIT  #: ended at gauge_max_sheet_length: no cut came
    NEW_STRIP = _capi.FLT_SHEET_FLAG_NEW_STRIP  #: ended by a long reversal or a jump
    NO_EDGES = _capi.FLT_SHEET_FLAG_NO_EDGES  #: strip edges unknown (NaN)
    NO_WAVE = _capi.FLT_SHEET_FLAG_NO_WAVE  #: no fiber has a wave (wave values NaN)
    EMPTY = _capi.FLT_SHEET_FLAG_EMPTY  #: no row: every result NaN and flagged
    #: coverage below gauge_min_coverage: shape and verdict "not judged"
    INCOMPLETE = _capi.FLT_SHEET_FLAG_INCOMPLETE
    #: rows lost: frames dropped, missing by the encoder, or lost lines
    LOST_ROWS = _capi.FLT_SHEET_FLAG_LOST_ROWS
    #: an early answer (gauge_provisional_mm): its last rows are estimates
    #: made before they were final; the final sheet with the same id follows
    PROVISIONAL = _capi.FLT_SHEET_FLAG_PROVISIONAL


# flt_sheet_value keys by the names Sheet.values uses (in key order), and
# the counters: generated from gauge.h (bindings/gen_tables.py).
# FLT_SHEET_FINISHED_TIME, FLT_SHEET_LATENCY and FLT_SHEET_CUT_TIME, times
# of the host's clock, are Sheet.finished_time, latency_s and cut_time: not
# among the values two runs of the same input share.
_TIMES = ("finished_time", "latency", "cut_time")
_VALUES = {name: key for name, key in _tables.SHEET_VALUES.items() if name not in _TIMES}

_COUNTERS = _tables.GAUGE_COUNTERS


@dataclass(frozen=True)
class SheetZones:
    """A sheet's zone profile, (zones,) arrays."""

    centre_x: np.ndarray  #: (zones,) zone centre across the sensor, mm (mean over the sheet)
    i_units: np.ndarray  #: (zones,) I-Units; NaN with ZONE_NO_DATA
    flags: np.ndarray  #: (zones,) uint8 ZONE_* bits
    strip_x: np.ndarray  #: (zones,) zone centre from the strip's centre line, mm


@dataclass(frozen=True)
class Sheet:
    """One measured sheet, copied out of the library (it stays valid for as
    long as it is referenced). A NaN value always comes with its flag:
    SheetFlag for the edges and the wave, the window flags (WINDOW_*) for
    bow and crossbow, the fiber and zone flags for the arrays."""

    id: int  #: number along the gauge's life, 1, 2, ...
    coil: int  #: number of its strip (coil), 1, 2, ...
    index: int  #: number within its coil, 1, 2, ...
    s_start: float  #: where it starts along the strip, mm (a cut, or its strip's head)
    s_end: float  #: where it ends, mm (a cut, the tail, a split)
    rows: int  #: rows (frames) in it
    s_first: float  #: s of its first row, mm (NaN with EMPTY)
    s_last: float  #: s of its last row, mm (NaN with EMPTY)
    strip_left: float  #: the strip's left edge, mm across the sensor (the extractor's edges)
    strip_right: float  #: its right edge, mm
    strip_width: float  #: its width, mm (mean over the sheet)
    strip_centre: float  #: its centre, mm (mean over the sheet)
    shape: Shape  #: the shape class
    confidence: float  #: in [0, 1]
    components: ShapeComponent  #: FLT_SHAPE_HAS_* bits
    bow_mm: float  #: coil-set sagitta over the sheet, mm
    crossbow_mm: float  #: transverse sagitta over the width, mm
    wave_height: float  #: the largest wave over the fibers: peak to peak, mm
    wave_period: float  #: its period, mm
    wave_steepness_percent: float  #: its steepness, %
    wave_x: float  #: the x of its fiber, mm
    max_i_units: float  #: the largest zone I-Units
    flags: SheetFlag  #: how it began and ended, what is NaN
    window_flags: int  #: the flatness window's WINDOW_* bits
    frames: int  #: frames measured (its rows)
    skipped: int  #: frames skipped (line stops, short reversals)
    dropped: int  #: frames dropped at a full queue
    saturated: int  #: saturated peaks on the strip (frames; 0 for pushed rows)
    invalid: int  #: samples (row, fiber) without a measurement
    lookahead_mm: float  #: strip the reconstructor had taken beyond s_end when finished
    fibers: FiberResults  #: per fiber: x, arc length, I-Units, wave, flags
    zones: SheetZones  #: per zone: centre, I-Units, flags, strip x
    fiber_strip_x: np.ndarray  #: (K,) result fibers from the strip's centre line, mm
    strip_width_range: Tuple[float, float]  #: smallest and largest width over the rows, mm
    strip_centre_range: Tuple[float, float]  #: smallest and largest centre over the rows, mm
    s: Optional[np.ndarray] = None  #: (rows,) row positions, mm (gauge_keep_maps >= 1)
    z: Optional[np.ndarray] = None  #: (rows, K) reconstructed heights, mm
    z_flags: Optional[np.ndarray] = None  #: (rows, K) uint8 FLAG_* bits
    measured: Optional[np.ndarray] = None  #: (rows, K) measured heights, mm (gauge_keep_maps 2)
    #: Every scalar result by its C name (flt_sheet_value), later ones too.
    values: Dict[str, float] = field(default_factory=dict)
    #: Its verdict, one result per rule of the rules it was judged by
    #: (Gauge.set_rules); None when the gauge had none.
    verdict: Optional[Tuple[RuleResult, ...]] = None
    #: Its coil's identity (Gauge.set_coil); None when the coil had none.
    coil_info: Optional[CoilInfo] = None
    #: The notes given while its rows were taken (Gauge.note).
    notes: Tuple["SheetNote", ...] = ()
    #: When it was finished, host UTC, s since 1970 (not compared: two runs
    #: of the same input finish at other times).
    finished_time: float = field(default=math.nan, compare=False)
    #: lookahead_mm in seconds, at the line speed the frames' times show:
    #: from the strip at s_end passing the sensor to the newest frame taken
    #: when the sheet's last row was finished (0 when it waited for none).
    latency_s: float = field(default=0.0, compare=False)
    #: When the strip at s_end passed the sensor, UTC, s since 1970 (the
    #: recording's time on a replay); finished_time - cut_time is the whole
    #: wait on a live line.
    cut_time: float = field(default=math.nan, compare=False)

    @property
    def provisional(self) -> bool:
        """An early answer (gauge_provisional_mm): its values and verdict may
        still change; the final sheet with the same id follows. Not counted,
        not archived, not in the coil's statistics."""
        return SheetFlag.PROVISIONAL in self.flags

    @property
    def failed_rules(self) -> int:
        """The number of rules the sheet failed (0 without rules)."""
        return int(self.values.get("rules_failed", 0))

    @property
    def coverage(self) -> float:
        """Rows measured over the rows its length should hold, 0..1 (below
        gauge_min_coverage the sheet is INCOMPLETE)."""
        return self.values["coverage"]

    @property
    def incomplete(self) -> bool:
        """True when too many rows are missing for a class or a verdict:
        ``shape`` is Shape.NOT_JUDGED and ``verdict_state`` NOT_JUDGED."""
        return bool(self.flags & SheetFlag.INCOMPLETE)

    @property
    def rows_expected(self) -> int:
        """The rows its length should hold (rows + dropped + missing)."""
        return int(self.values["rows_expected"])

    @property
    def rows_measured(self) -> int:
        """Its rows that measured the strip (rows - lost_lines)."""
        return int(self.values["rows_measured"])

    @property
    def lost_lines(self) -> int:
        """Rows inside the strip whose frame did not show it."""
        return int(self.values["lost_lines"])

    @property
    def missing(self) -> int:
        """Frames missing by the encoder (lost before the gauge saw them)."""
        return int(self.values["missing"])

    @property
    def verdict_state(self) -> VerdictState:
        """The whole sheet's verdict: FAIL when a rule failed, PASS when every
        rule was judged and passed, else NOT_JUDGED (no rules, a rule that
        could not judge it, or an incomplete sheet): never a pass."""
        return VerdictState(int(self.values["verdict"]))


@dataclass(frozen=True)
class RuleStats:
    """One rule's statistics over a coil (flt_gauge_coil_stats)."""

    rule: int  #: the rule's index in the rule set
    passed: int  #: sheets that passed it
    failed: int  #: sheets that failed it
    no_band: int  #: sheets none of its bands covers
    not_measured: int  #: sheets its measure was missing on
    worst_min: float  #: the smallest worst value of the sheets measured (NaN: none)
    worst_max: float  #: the largest
    worst_mean: float  #: their mean
    worst_sheet: float  #: the id of the sheet with the largest (NaN: none)
    worst_x_mm: float  #: where the largest is, across the strip, mm
    worst_s_mm: float  #: ... and along it, mm
    #: (20,) sheets by worst / limit: bin i counts (i/10, (i+1)/10] (bin 0
    #: from 0, bin 19 everything above 1.9): bins 0-9 passed, 10-19 failed.
    histogram: np.ndarray
    not_judged: int = 0  #: incomplete sheets (not judged by any rule)


@dataclass(frozen=True)
class CoilStats:
    """A coil's verdict statistics (flt_gauge_coil_stats). Every sheet is
    passed, failed or not judged: a sheet that no rule's band covers, whose
    measure is missing, or that is incomplete is never counted as passed."""

    coil: int  #: the coil's number (0: no sheet judged yet)
    sheets: int  #: sheets evaluated under the rules: passed + failed + not_judged
    passed: int  #: sheets every rule judged and passed
    failed: int  #: sheets that failed at least one rule
    finished: bool  #: its last sheet was judged
    rules: Tuple[RuleStats, ...]  #: per rule, in rule order
    not_judged: int = 0  #: sheets no rule failed that some rule could not judge

    @property
    def judged(self) -> int:
        """Sheets judged: passed + failed."""
        return self.passed + self.failed


@dataclass(frozen=True)
class SheetNote:
    """A note given with Gauge.note (a leveler change, a remark)."""

    kind: str  #: what it is ("leveler")
    text: str  #: what it says
    s_mm: float  #: where it took effect along the strip, mm


def _read_sheet(handle: Any, maps: int) -> Sheet:
    v = {name: float(_capi.flt_sheet_get(handle, key)) for name, key in _VALUES.items()}
    fibers, zones, rows = int(v["fibers"]), int(v["zones"]), int(v["rows"])

    def array(key: int, n: int) -> np.ndarray:
        out = np.empty(n)
        handle.array_into(key, out)
        out.flags.writeable = False
        return out

    fiber_flags = array(_capi.FLT_SHEET_FIBER_FLAGS, fibers).astype(np.uint8)
    fiber_results = FiberResults(
        array(_capi.FLT_SHEET_FIBER_X, fibers),
        array(_capi.FLT_SHEET_FIBER_ARC_LENGTH, fibers),
        array(_capi.FLT_SHEET_FIBER_I_UNITS, fibers),
        array(_capi.FLT_SHEET_FIBER_WAVE_HEIGHT, fibers),
        array(_capi.FLT_SHEET_FIBER_WAVE_PERIOD, fibers),
        array(_capi.FLT_SHEET_FIBER_STEEPNESS, fibers),
        fiber_flags,
    )
    zone_results = SheetZones(
        array(_capi.FLT_SHEET_ZONE_CENTRE_X, zones),
        array(_capi.FLT_SHEET_ZONE_I_UNITS, zones),
        array(_capi.FLT_SHEET_ZONE_FLAGS, zones).astype(np.uint8),
        array(_capi.FLT_SHEET_ZONE_STRIP_X, zones),
    )
    verdict = None
    if int(v["rules"]) > 0:
        rules_h, verdict_h = _capi.flt_sheet_verdict(handle)
        verdict = tuple(_results(verdict_h, _rule_list(rules_h)))
    s = z = z_flags = measured = None
    if maps >= 1:
        s = np.empty(rows)
        z = np.empty((rows, fibers))
        z_flags = np.empty((rows, fibers), dtype=np.uint8)
        handle.height_map_into(s, z, z_flags)
    if maps >= 2:
        measured = np.empty((rows, fibers))
        handle.measured_map_into(measured)
    try:
        coil_info: Optional[CoilInfo] = CoilInfo._from_handle(_capi.flt_sheet_coil(handle))
    except NotFoundError:
        coil_info = None
    notes = tuple(SheetNote(*_capi.flt_sheet_note(handle, i))
                  for i in range(int(_capi.flt_sheet_note_count(handle))))
    return Sheet(
        int(v["id"]), int(v["coil"]), int(v["index"]), v["s_start"], v["s_end"], rows,
        v["s_first"], v["s_last"], v["strip_left"], v["strip_right"], v["strip_width"],
        v["strip_centre"], Shape(int(v["shape"])), v["confidence"],
        ShapeComponent(int(v["components"])), v["bow"], v["crossbow"], v["wave_height"],
        v["wave_period"], v["wave_steepness"], v["wave_x"], v["max_i_units"],
        SheetFlag(int(v["flags"])), int(v["window_flags"]), int(v["frames"]),
        int(v["skipped"]), int(v["dropped"]), int(v["saturated"]), int(v["invalid"]),
        v["lookahead"], fiber_results, zone_results,
        array(_capi.FLT_SHEET_FIBER_STRIP_X, fibers),
        (v["strip_width_min"], v["strip_width_max"]),
        (v["strip_centre_min"], v["strip_centre_max"]), s, z, z_flags, measured, v, verdict,
        coil_info, notes, float(_capi.flt_sheet_get(handle, _capi.FLT_SHEET_FINISHED_TIME)),
        float(_capi.flt_sheet_get(handle, _capi.FLT_SHEET_LATENCY)),
        float(_capi.flt_sheet_get(handle, _capi.FLT_SHEET_CUT_TIME)))


def gauge_options() -> Dict[str, float]:
    """The gauge's own options (gauge_*) with their C defaults. A Gauge also
    takes the reconstructor's, the extractor's (extract_*) and the flatness
    metrics' (flat_*) options."""
    return {name: info.default for name, info in prefixed_options("gauge_").items()}


class Gauge:
    """One handle that runs a line: frames (or profile rows) and the shear's
    cuts in, measured sheets out (flatline/gauge.h).

    Args:
        calib: the sensor's finished :class:`Calibration` (frame size, laser
            spacing, fiber grid: every geometric constant comes from it).
        **options: the reconstructor's, extractor's (extract_*), flatness
            (flat_*) and gauge (gauge_*) options by their C names; another
            component's option (sim_*, source_*) raises InvalidArgumentError.

    Frames go in with :meth:`push_frame` (or :meth:`push_row`), or from a
    :class:`Source` the gauge acquires from on a thread of its own
    (:meth:`attach`, :meth:`start`, :meth:`stop`). :meth:`cut` tells where
    the shear cut, before or after the strip gets there. Sheets come out in
    order: iterate the gauge for the sheets waiting now, or
    :meth:`sheets` to wait for them as they come; :meth:`flush` ends the
    strip (its last sheet) at the end of the input.

        with flatline.Gauge(calib, rigid_motion=True, robust="huber") as gauge:
            gauge.cut(3000.0)
            for frame in frames:
                gauge.push_frame(frame.pixels, frame.encoder_mm)
                for sheet in gauge:
                    print(sheet.id, sheet.shape, sheet.max_i_units)
            gauge.flush()
            for sheet in gauge:
                ...

    Nothing is lost by default: a push waits for room in a full queue
    (gauge_overflow="auto"; an attached camera drops instead, counted and
    flagged on its sheet), and every finished sheet waits to be read. A
    sheet missing more than 5 % of its rows (gauge_min_coverage) is
    ``incomplete``: its shape and verdict say "not judged".

    Frames come from one thread at a time, in order: a push from a second
    thread while one is in progress raises StateError (nothing taken, the
    gauge goes on); iterating sheets may run on another thread. The GIL is released while the gauge waits
    (a full queue, flush, stop, a sheet). While an
    attached source is acquiring, leave it (and the simulator or bus it
    reads) alone: the gauge's thread uses it.

    Options:
{options}
    """

    def __init__(self, calib: Calibration, **options: OptionValue) -> None:
        fn = "Gauge"
        if not isinstance(calib, Calibration):
            raise TypeError(f"{fn}() argument 'calib' must be a Calibration, not "
                            f"{type(calib).__name__}")
        bag = make_options(fn, options)
        with calib._reading():
            handle = _capi.flt_gauge_create(calib._live(), bag)
        self._handle: Optional[_capi.flt_gauge] = handle
        self._source: Optional[Source] = None
        # The recorder's and the archive's C handles the gauge borrows: held
        # here, so that closing the Python object first cannot free them.
        self._recorder_handle: Any = None
        self._archive_handle: Any = None
        self._maps = int(_capi.flt_gauge_get_option(handle, _capi.FLT_OPT_GAUGE_KEEP_MAPS))
        self._rules: Optional[ToleranceRules] = None
        self._fibers = int(calib.fiber_grid.count)
        width, height = calib.frame_size
        self._frame_shape = (height, width)

    # -- lifetime -------------------------------------------------------------------

    def close(self) -> None:
        """Stops the acquisition and the workers and frees everything now
        (unfinished sheets are dropped). Idempotent; later calls raise
        StateError."""
        self._handle = None  # the C gauge first: it borrows what follows
        self._source = None
        self._recorder_handle = None
        self._archive_handle = None

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._handle is None

    def __enter__(self) -> "Gauge":
        self._live()
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def __del__(self) -> None:
        # The C gauge must stop before the source it borrows goes.
        if getattr(self, "_handle", None) is not None:
            self._handle = None

    def _live(self) -> _capi.flt_gauge:
        handle = self._handle
        if handle is None:
            raise StateError("the Gauge is closed")
        return handle

    def __repr__(self) -> str:
        if getattr(self, "_handle", None) is None:
            return "<flatline.Gauge closed>"
        return f"<flatline.Gauge {self._fibers} fibers>"

    def option(self, name: str) -> float:
        """The effective value of an option: the gauge's, and the
        reconstructor's as the gauge set them (laser_spacing from the
        calibration, row_capacity from its latency)."""
        key = _capi.flt_option_find(name)
        return float(_capi.flt_gauge_get_option(self._live(), key))

    # -- input ----------------------------------------------------------------------

    def push_frame(self, frame: np.ndarray, encoder_mm: float,
                   format: Optional[PixelFormat] = None) -> None:
        """One camera frame: (height, width) uint8 (Mono8) or uint16 pixels
        (Mono16 unless `format` says Mono10 or Mono12), taken at encoder_mm.
        Copied: the array may be reused at once. Skipped and dropped frames
        are counted, not raised (:meth:`counters`)."""
        fn = "push_frame"
        if not isinstance(frame, np.ndarray):
            raise TypeError(f"{fn}() argument 'frame' must be a numpy array, not "
                            f"{type(frame).__name__}")
        if frame.dtype.kind != "u" or frame.dtype.itemsize not in (1, 2):
            raise TypeError(f"{fn}() argument 'frame' has dtype {frame.dtype}; frames are "
                            f"uint8 (Mono8) or uint16 (Mono10/12/16)")
        if format is None:
            fmt = PixelFormat.MONO8 if frame.dtype.itemsize == 1 else PixelFormat.MONO16
        else:
            fmt = PixelFormat(format)
            if fmt.dtype.itemsize != frame.dtype.itemsize:
                raise TypeError(f"{fn}() argument 'frame' has dtype {frame.dtype}, but "
                                f"{fmt.name} frames are {fmt.dtype}")
        check_one_channel(fn, frame)
        if frame.shape != self._frame_shape:
            raise ValueError(f"{fn}() argument 'frame' has shape {frame.shape}, but the "
                             f"calibration's frames are {self._frame_shape} (height, width)")
        item = frame.dtype.itemsize
        if not (frame.flags.aligned and frame.dtype.isnative and frame.strides[1] == item
                and frame.strides[0] >= frame.shape[1] * item):
            frame = np.ascontiguousarray(frame, dtype=frame.dtype.newbyteorder("="))
        encoder_mm = as_real(fn, "encoder_mm", encoder_mm)
        # One producer at a time: the library refuses a second thread that
        # pushes meanwhile (StateError) rather than interleave its frames.
        self._live().push_frame_array(frame, int(fmt), encoder_mm)

    def push_row(self, encoder_mm: float, height: Any, slope: Any,
                 valid: Any = None) -> None:
        """One profile row instead of a frame (a sensor that extracts its own
        profiles): height (K,) mm, slope (K,) mm/mm, valid (K,) bool or None
        (then finite values are valid), at the frame's encoder position."""
        fn = "push_row"
        encoder_mm = as_real(fn, "encoder_mm", encoder_mm)
        h = as_float64(fn, "height", height, 1)
        g = as_float64(fn, "slope", slope, 1)
        if valid is None:
            mask, flagged = np.zeros(1, dtype=np.uint8), 0
        else:
            mask, flagged = as_mask(fn, "valid", valid, 1), 1
        self._live().push_row_arrays(encoder_mm, h, g, mask, flagged)

    def cut(self, encoder_mm: float) -> None:
        """The shear cut the strip at encoder_mm (the reading at which the cut
        line lies midway between the lasers), before or after the strip gets
        there; cuts come in increasing order."""
        _capi.flt_gauge_cut(self._live(), as_real("cut", "encoder_mm", encoder_mm))

    def flush(self) -> None:
        """The end of the input: processes every frame pushed, ends the strip
        (its last sheet) and waits until that sheet is out (after a push
        another thread has in progress)."""
        try:
            self._live().flush_waiting()
        finally:
            _log.drain()

    # -- acquisition ----------------------------------------------------------------

    def attach(self, source: Optional[Source]) -> None:
        """Acquires from `source` (kept alive by the gauge) on :meth:`start`;
        None detaches. StateError while acquiring."""
        if source is not None and not isinstance(source, Source):
            raise TypeError(f"attach() argument 'source' must be a Source or None, not "
                            f"{type(source).__name__}")
        handle = None if source is None else source._live()
        _capi.flt_gauge_attach_source(self._live(), handle)
        self._source = source

    # -- the quality record ---------------------------------------------------------

    def set_coil(self, coil: Optional[CoilInfo]) -> None:
        """The coil the next strip is (or the strip under the sensor, when it
        has no identity yet): its sheets, statistics and verdicts carry it,
        and its nominal thickness and width, where given, choose the rule
        bands. Takes effect with the next frame; None: no identity."""
        if coil is not None and not isinstance(coil, CoilInfo):
            raise TypeError(f"set_coil() argument 'coil' must be a CoilInfo or None, not "
                            f"{type(coil).__name__}")
        _capi.flt_gauge_set_coil(self._live(), None if coil is None else coil._handle())

    def coil_info(self, last: bool = False) -> Optional[CoilInfo]:
        """The identity of the coil being measured (or, with last=True, of
        the last finished one), None when it has none."""
        which = _capi.FLT_COIL_LAST if last else _capi.FLT_COIL_CURRENT
        try:
            return CoilInfo._from_handle(_capi.flt_gauge_coil_info(self._live(), which))
        except NotFoundError:
            return None

    def note(self, kind: str, text: str) -> None:
        """A note from the next frame on (a leveler change: kind "leveler"),
        given to the sheet whose rows begin there, recorded and archived."""
        _capi.flt_gauge_note(self._live(), kind, text)

    def attach_recorder(self, recorder: Optional[Recorder]) -> None:
        """Records the gauge's input from the next frame on (kept alive by
        the gauge); None stops. Only while idle (before the first frame, or
        after flush); the rows are measured as recorded (quantized)."""
        if recorder is not None and not isinstance(recorder, Recorder):
            raise TypeError(f"attach_recorder() argument 'recorder' must be a Recorder or "
                            f"None, not {type(recorder).__name__}")
        handle = None if recorder is None else recorder._live()
        _capi.flt_gauge_attach_recorder(self._live(), handle)
        self._recorder_handle = handle

    def attach_archive(self, archive: Optional[Archive]) -> None:
        """Archives every sheet finished from now on (kept alive by the
        gauge); None stops. Only while idle, as attach_recorder."""
        if archive is not None and not isinstance(archive, Archive):
            raise TypeError(f"attach_archive() argument 'archive' must be an Archive or "
                            f"None, not {type(archive).__name__}")
        handle = None if archive is None else archive._live()
        _capi.flt_gauge_attach_archive(self._live(), handle)
        self._archive_handle = handle

    def start(self) -> None:
        """Starts the attached source and the gauge's acquisition thread."""
        _capi.flt_gauge_start(self._live())

    def stop(self) -> None:
        """Stops the acquisition and waits until its frames are processed (the
        strip stays open: :meth:`flush` ends it). Raises the error that ended
        the acquisition by itself, e.g. DeviceError for an unplugged camera."""
        try:
            self._live().stop_waiting()
        finally:
            _log.drain()

    def run(self, source: Source) -> Iterator[Sheet]:
        """Runs a finite source (an image sequence, a recording) to its end
        and yields every sheet, in order, as it comes: attaches and starts
        the source, and after its last frame ends the strip (a flush), so
        the last sheet comes too, then detaches the source. The source's
        own error (e.g. a file it cannot read) is raised after the sheets
        before it. Closing the iterator early stops the acquisition.

            for sheet in gauge.run(flatline.Source.images("recording/")):
                print(sheet.id, sheet.shape, sheet.max_i_units)
        """
        if not isinstance(source, Source):
            raise TypeError(f"run() argument 'source' must be a Source, not "
                            f"{type(source).__name__}")
        self.attach(source)
        self.start()
        ended = False
        try:
            while True:
                try:
                    self._live().wait_waiting(50)
                    ended = True
                    _log.drain()
                    break
                except TimeoutError:
                    yield from self  # the sheets so far; the source goes on
                except FlatlineError:
                    ended = True  # the strip was ended all the same
                    yield from self
                    raise
            yield from self
        finally:
            if self._handle is not None:
                if not ended:
                    try:
                        self.stop()
                    except FlatlineError:
                        pass  # closed early: why the source would have ended is moot
                self.attach(None)  # the source may be closed after the run

    # -- output ---------------------------------------------------------------------

    def next_sheet(self, timeout: float = 0.0) -> Optional[Sheet]:
        """The next finished sheet, waiting up to `timeout` seconds; None if
        none came."""
        seconds = as_real("next_sheet", "timeout", timeout)
        if not seconds >= 0:
            raise ValueError(f"next_sheet() argument 'timeout' must be >= 0, got {timeout}")
        ms = int(min(seconds, 4e6) * 1000.0)
        handle = self._live().next_sheet_waiting(ms)
        _log.drain()
        if handle is None:
            return None
        try:
            return _read_sheet(handle, self._maps)
        finally:
            del handle  # the slot goes back to the gauge at once

    def __iter__(self) -> Iterator[Sheet]:
        """The sheets finished so far, oldest first (without waiting)."""
        while True:
            sheet = self.next_sheet()
            if sheet is None:
                return
            yield sheet

    def sheets(self, timeout: float = 1.0) -> Iterator[Sheet]:
        """Sheets as they come: each waited for up to `timeout` seconds; the
        iteration ends when none came in that time (e.g. after :meth:`stop`
        and :meth:`flush`)."""
        while True:
            sheet = self.next_sheet(timeout)
            if sheet is None:
                return
            yield sheet

    # -- verdicts --------------------------------------------------------------------

    @property
    def rules(self) -> Optional[ToleranceRules]:
        """The rule set sheets are judged by (set_rules), or None."""
        return self._rules

    def set_rules(self, rules: Optional[ToleranceRules],
                  thickness_mm: Optional[float] = None,
                  width_mm: Union[float, str, None] = None) -> None:
        """Judges every sheet from now on against `rules` (None: no more).
        The sheets' thickness (mm) and width choose each rule's band, and
        both are required with rules: ``width_mm`` is the nominal width
        (mm) or ``"measured"`` for each sheet's measured strip width. A
        sheet that no band covers is not judged (never passed). The gauge
        keeps its own copy. The current coil's statistics restart; set the
        rules before a coil's first frame.

            gauge.set_rules(rules, thickness_mm=4.0, width_mm="measured")
        """
        fn = "set_rules"
        if rules is not None and not isinstance(rules, ToleranceRules):
            raise TypeError(f"{fn}() argument 'rules' must be ToleranceRules or None, not "
                            f"{type(rules).__name__}")
        if rules is None:
            _capi.flt_gauge_set_rules(self._live(), None, 1.0, 0.0)
            self._rules = None
            return
        if thickness_mm is None:
            raise TypeError(f"{fn}() missing required argument 'thickness_mm': the sheets' "
                            f"thickness, mm, chooses each rule's band (there is no default)")
        if width_mm is None:
            raise TypeError(f"{fn}() missing required argument 'width_mm': the sheets' "
                            f"nominal width, mm, or \"measured\" for each sheet's strip width")
        if isinstance(width_mm, str):
            if width_mm != "measured":
                raise ValueError(f"{fn}() argument 'width_mm' = {width_mm!r} must be a width "
                                 f"in mm or \"measured\"")
            width = _capi.FLT_GAUGE_WIDTH_MEASURED
        else:
            width = as_real(fn, "width_mm", width_mm)
            if width == 0.0:
                raise ValueError(f"{fn}() argument 'width_mm' = 0: give the nominal width in "
                                 f"mm, or \"measured\" for each sheet's strip width")
        _capi.flt_gauge_set_rules(self._live(), rules._handle,
                                  as_real(fn, "thickness_mm", thickness_mm), width)
        self._rules = rules

    def coil_stats(self, last: bool = False) -> Optional[CoilStats]:
        """The verdict statistics of the coil being measured, or with
        last=True of the last finished coil; None when there are none (no
        rules, no coil finished yet)."""
        handle = self._live()
        which = _capi.FLT_COIL_LAST if last else _capi.FLT_COIL_CURRENT
        first = np.empty(_capi.FLT_COIL_VALUES)
        try:
            handle.coil_stats_into(which, 0, first)
        except StateError:
            return None
        rows = [first]
        for i in range(1, int(first[_capi.FLT_COIL_RULES])):
            row = np.empty(_capi.FLT_COIL_VALUES)
            handle.coil_stats_into(which, i, row)
            rows.append(row)
        h0 = _capi.FLT_COIL_HISTOGRAM
        stats = []
        for i, row in enumerate(rows):
            hist = row[h0:h0 + _capi.FLT_COIL_HISTOGRAM_BINS].astype(np.int64)
            hist.flags.writeable = False
            stats.append(RuleStats(
                i, int(row[_capi.FLT_COIL_RULE_PASSED]), int(row[_capi.FLT_COIL_RULE_FAILED]),
                int(row[_capi.FLT_COIL_RULE_NO_BAND]), int(row[_capi.FLT_COIL_RULE_NOT_MEASURED]),
                float(row[_capi.FLT_COIL_WORST_MIN]), float(row[_capi.FLT_COIL_WORST_MAX]),
                float(row[_capi.FLT_COIL_WORST_MEAN]), float(row[_capi.FLT_COIL_WORST_SHEET]),
                float(row[_capi.FLT_COIL_WORST_X]), float(row[_capi.FLT_COIL_WORST_S]), hist,
                int(row[_capi.FLT_COIL_RULE_NOT_JUDGED])))
        return CoilStats(int(first[_capi.FLT_COIL_NUMBER]), int(first[_capi.FLT_COIL_SHEETS]),
                         int(first[_capi.FLT_COIL_SHEETS_PASSED]),
                         int(first[_capi.FLT_COIL_SHEETS_FAILED]),
                         bool(first[_capi.FLT_COIL_FINISHED]), tuple(stats),
                         int(first[_capi.FLT_COIL_SHEETS_NOT_JUDGED]))

    def counters(self) -> Dict[str, int]:
        """The gauge's counters by name: frames, extracted, skipped_stop,
        skipped_reversal, dropped, no_strip, strips, sheets, sheets_dropped,
        cuts, cuts_ignored, reversals, extract_errors, queued, acquiring,
        sheets_waiting."""
        handle = self._live()
        return {name: int(_capi.flt_gauge_count(handle, key)) for name, key in _COUNTERS.items()}


def _document_options() -> None:
    names = [name for name, info in prefixed_options("gauge_").items()]
    if Gauge.__doc__:
        Gauge.__doc__ = Gauge.__doc__.replace("{options}", options_doc(names))


_document_options()
