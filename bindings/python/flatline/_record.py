# SPDX-License-Identifier: Apache-2.0
"""The quality record (flatline/coil.h, flatline/record.h): coil
identities, recordings of a gauge's input and the archive of its sheets.

A :class:`Recorder` writes a recording (an SQLite file: docs/record.md
documents it for readers without libflatline), a :class:`Recording` reads
one back, and ``Source.open_recording`` replays it through a gauge. An
:class:`Archive` keeps every finished sheet in an SQLite file or on a
PostgreSQL server; ``python -m flatline.report`` turns a coil of it into a
report a quality engineer signs."""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from typing import Any, Dict, Mapping, NamedTuple, Optional

import numpy as np

from . import capi as _capi
from ._arrays import as_float64, as_mask
from ._calib import Calibration, PathLike, _path
from ._errors import StateError
from ._options import OptionValue, make_options, prefixed_options

__all__ = [
    "CoilInfo",
    "Recorder",
    "Recording",
    "RecordedRows",
    "Archive",
    "record_options",
    "archive_options",
]

_FIELDS = (
    ("coil_id", _capi.FLT_COIL_FIELD_ID),
    ("order", _capi.FLT_COIL_FIELD_ORDER),
    ("heat", _capi.FLT_COIL_FIELD_HEAT),
    ("grade", _capi.FLT_COIL_FIELD_GRADE),
    ("customer", _capi.FLT_COIL_FIELD_CUSTOMER),
)


@dataclass(frozen=True)
class CoilInfo:
    """A coil's identity as the mill's systems name it (flatline/coil.h):
    carried by every sheet of the coil, its verdicts (the nominal thickness
    and width choose the rule bands) and its statistics, and stored in
    recordings and the archive. Texts are UTF-8, at most 256 bytes, without
    control characters; extras are free key/value pairs (keys of ASCII
    letters, digits, '_', '-', '.')."""

    coil_id: str  #: the coil's id ("4711"); never empty
    order: str = ""  #: the production order
    heat: str = ""  #: the heat (melt)
    grade: str = ""  #: the steel grade ("S355MC")
    customer: str = ""  #: the customer
    thickness_mm: float = 0.0  #: nominal thickness, mm (0: not given)
    width_mm: float = 0.0  #: nominal width, mm (0: not given)
    extras: Mapping[str, str] = field(default_factory=dict)  #: free key/value pairs

    def _handle(self) -> _capi.flt_coil_info:
        """A C handle holding this identity (the library checks every
        field and raises InvalidArgumentError naming it)."""
        if not isinstance(self.coil_id, str):
            raise TypeError(f"CoilInfo.coil_id must be a str, not {type(self.coil_id).__name__}")
        handle = _capi.flt_coil_info_create(self.coil_id)
        for name, key in _FIELDS[1:]:
            value = getattr(self, name)
            if not isinstance(value, str):
                raise TypeError(f"CoilInfo.{name} must be a str, not {type(value).__name__}")
            if value:
                _capi.flt_coil_info_set_text(handle, key, value)
        _capi.flt_coil_info_set_nominal(handle, float(self.thickness_mm), float(self.width_mm))
        for key, value in dict(self.extras).items():
            if not isinstance(key, str) or not isinstance(value, str):
                raise TypeError("CoilInfo.extras must map str to str")
            _capi.flt_coil_info_set_extra(handle, key, value)
        return handle

    @classmethod
    def _from_handle(cls, handle: Any) -> "CoilInfo":
        """A copy of a C identity (owned or lent)."""
        texts = {name: _capi.flt_coil_info_get_text(handle, key) for name, key in _FIELDS}
        thickness, width = _capi.flt_coil_info_get_nominal(handle)
        extras = {}
        for i in range(int(_capi.flt_coil_info_extra_count(handle))):
            key, value = _capi.flt_coil_info_extra(handle, i)
            extras[key] = value
        return cls(thickness_mm=float(thickness), width_mm=float(width), extras=extras, **texts)


def record_options() -> Dict[str, float]:
    """The recorder's options (record_*) with their C defaults."""
    return {name: info.default for name, info in prefixed_options("record_").items()}


def archive_options() -> Dict[str, float]:
    """The archive's options (archive_*) with their C defaults."""
    return {name: info.default for name, info in prefixed_options("archive_").items()}


_RECORDER_COUNTERS = {
    "rows": _capi.FLT_RECORDER_COUNT_ROWS,
    "rows_stored": _capi.FLT_RECORDER_COUNT_ROWS_STORED,
    "rows_lost": _capi.FLT_RECORDER_COUNT_ROWS_LOST,
    "blocks": _capi.FLT_RECORDER_COUNT_BLOCKS,
    "commits": _capi.FLT_RECORDER_COUNT_COMMITS,
    "bytes": _capi.FLT_RECORDER_COUNT_BYTES,
    "samples": _capi.FLT_RECORDER_COUNT_SAMPLES,
    "frames": _capi.FLT_RECORDER_COUNT_FRAMES,
    "frames_lost": _capi.FLT_RECORDER_COUNT_FRAMES_LOST,
    "events": _capi.FLT_RECORDER_COUNT_EVENTS,
    "writer_ns": _capi.FLT_RECORDER_COUNT_WRITER_NS,
}


class _Handle:
    """The life cycle the three classes share: close() frees the C object
    now, a closed object raises StateError, `with` closes."""

    _what = "object"

    def __init__(self, handle: Any) -> None:
        self._handle: Optional[Any] = handle

    def close(self) -> None:
        """Frees the C object now (for a recorder or an archive: writes what
        is pending first). Idempotent."""
        self._handle = None

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._handle is None

    def _live(self) -> Any:
        handle = self._handle
        if handle is None:
            raise StateError(f"the {self._what} is closed")
        return handle

    def __enter__(self):  # type: ignore[no-untyped-def]
        self._live()
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()


class Recorder(_Handle):
    """Writes a recording (flatline/record.h): attach it to a gauge
    (``Gauge.attach_recorder``) and the gauge records every row it takes,
    its cuts and coils; or write rows yourself with :meth:`push_row` (a
    sensor that extracts its own profiles). A killed process or a power cut
    loses at most about twice record_commit_interval (250 ms by default).

    Args:
        path: the file to create (an existing file is refused).
        calib: the sensor's finished :class:`Calibration` (stored in the file).
        **options: record_* options (:func:`record_options`).
    """

    _what = "Recorder"

    def __init__(self, path: PathLike, calib: Calibration, **options: OptionValue) -> None:
        fn = "Recorder"
        if not isinstance(calib, Calibration):
            raise TypeError(f"{fn}() argument 'calib' must be a Calibration, not "
                            f"{type(calib).__name__}")
        bag = make_options(fn, options, prefixes=("record_",))
        with calib._reading():
            handle = _capi.flt_recorder_create(_path(fn, path), calib._live(), bag)
        super().__init__(handle)
        self._fibers = int(calib.fiber_grid.count)

    def push_row(self, encoder_mm: float, height: Any, slope: Any, valid: Any = None) -> None:
        """One profile row, as Gauge.push_row takes it: height (K,) mm,
        slope (K,) mm/mm, valid (K,) bool or None (finite values valid)."""
        fn = "push_row"
        h = as_float64(fn, "height", height, 1)
        g = as_float64(fn, "slope", slope, 1)
        if valid is None:
            mask, flagged = np.zeros(1, dtype=np.uint8), 0
        else:
            mask, flagged = as_mask(fn, "valid", valid, 1), 1
        self._live().push_row_arrays(float(encoder_mm), h, g, mask, flagged)

    def cut(self, encoder_mm: float) -> None:
        """The shear cut at encoder_mm, before the next row."""
        _capi.flt_recorder_cut(self._live(), float(encoder_mm))

    def set_coil(self, coil: CoilInfo) -> None:
        """A coil's identity, before the next row."""
        if not isinstance(coil, CoilInfo):
            raise TypeError(f"set_coil() argument 'coil' must be a CoilInfo, not "
                            f"{type(coil).__name__}")
        _capi.flt_recorder_set_coil(self._live(), coil._handle())

    def sync(self, timeout_ms: int = 10000) -> None:
        """Waits until everything given so far is on the disk
        (TimeoutError after timeout_ms)."""
        self._live().sync_waiting(int(timeout_ms))

    def save_frames(self) -> None:
        """Writes the raw frames kept in the ring (record_frames="ring")."""
        _capi.flt_recorder_save_frames(self._live())

    def counters(self) -> Dict[str, int]:
        """Rows given, stored and lost, blocks, commits, bytes, samples,
        frames, events and the writer thread's busy time (ns)."""
        handle = self._live()
        return {name: int(_capi.flt_recorder_count(handle, key))
                for name, key in _RECORDER_COUNTERS.items()}


class RecordedRows(NamedTuple):
    """Rows of a recording as the gauge measured them."""

    encoder_mm: np.ndarray  #: (n,) encoder positions, mm
    time_s: np.ndarray  #: (n,) host UTC times, s since 1970
    height: np.ndarray  #: (n, fibers) mm; NaN where flags != 0
    slope: np.ndarray  #: (n, fibers) mm/mm; NaN where flags != 0
    flags: np.ndarray  #: (n, fibers) uint8: 0, FLAG_INVALID_INPUT or FLAG_OFF_STRIP


class Recording(_Handle):
    """A recording opened for reading (also one still being written, or
    one whose writer was killed). :meth:`verify` checks every block's
    CRC-32; :meth:`read_rows` returns rows as numpy arrays; replay it
    through a gauge with ``Source.open_recording``."""

    _what = "Recording"

    def __init__(self, path: PathLike) -> None:
        super().__init__(_capi.flt_recording_open(_path("Recording", path)))

    def _info(self, key: int) -> float:
        return float(_capi.flt_recording_info(self._live(), key))

    @property
    def version(self) -> int:
        """The file's format version."""
        return int(self._info(_capi.FLT_RECORDING_VERSION_OF))

    @property
    def fibers(self) -> int:
        """Fibers per row."""
        return int(self._info(_capi.FLT_RECORDING_FIBERS))

    @property
    def rows(self) -> int:
        """Rows stored."""
        return int(self._info(_capi.FLT_RECORDING_ROWS))

    @property
    def rows_lost(self) -> int:
        """Rows the writer marked as lost (0 when it kept up)."""
        return int(self._info(_capi.FLT_RECORDING_ROWS_LOST))

    @property
    def quantum_mm(self) -> float:
        """The height quantum, mm."""
        return self._info(_capi.FLT_RECORDING_QUANTUM)

    @property
    def frames(self) -> int:
        """Raw camera frames stored."""
        return int(self._info(_capi.FLT_RECORDING_FRAMES))

    @property
    def time_range(self) -> "tuple[float, float]":
        """UTC time of the first and the last row, s since 1970 (NaN
        without rows)."""
        return (self._info(_capi.FLT_RECORDING_FIRST_TIME),
                self._info(_capi.FLT_RECORDING_LAST_TIME))

    def calibration(self) -> Calibration:
        """The calibration the recording was made with."""
        return Calibration._wrap(_capi.flt_recording_calib(self._live()))

    def options(self) -> Dict[str, float]:
        """The options of the gauge that made the recording, by name (empty
        when none were recorded): Gauge(calib, **options) replays it
        exactly."""
        if not self._info(_capi.FLT_RECORDING_HAS_OPTIONS):
            return {}
        bag = _capi.flt_recording_options(self._live())
        out = {}
        for name, info in prefixed_options("gauge_", "extract_", "flat_").items():
            out[name] = float(_capi.flt_options_get(bag, info.key))
        from ._recon import reconstructor_options
        for name in reconstructor_options():
            key = _capi.flt_option_find(name)
            out[name] = float(_capi.flt_options_get(bag, key))
        return out

    def verify(self) -> None:
        """Checks every block (its CRC-32, and that it decodes); raises
        FormatError naming the first bad one."""
        self._live().verify_waiting()

    def read_rows(self, first: int = 0, count: Optional[int] = None) -> RecordedRows:
        """Stored rows [first, first + count) (all from `first` by
        default), clipped at the last."""
        handle = self._live()
        total = self.rows
        first = int(first)
        if first < 0:
            raise ValueError("read_rows() argument 'first' must be >= 0")
        n = max(0, total - first) if count is None else max(0, min(int(count), total - first))
        k = self.fibers
        e = np.empty(n)
        t = np.empty(n)
        h = np.empty((n, k))
        s = np.empty((n, k))
        f = np.empty((n, k), dtype=np.uint8)
        got = int(handle.read_rows_into(first, e, t, h, s, f))
        return RecordedRows(e[:got], t[:got], h[:got], s[:got], f[:got])


_ARCHIVE_COUNTERS = {
    "sheets": _capi.FLT_ARCHIVE_COUNT_SHEETS,
    "stored": _capi.FLT_ARCHIVE_COUNT_STORED,
    "pending": _capi.FLT_ARCHIVE_COUNT_PENDING,
    "lost": _capi.FLT_ARCHIVE_COUNT_LOST,
    "failures": _capi.FLT_ARCHIVE_COUNT_FAILURES,
    "reconnects": _capi.FLT_ARCHIVE_COUNT_RECONNECTS,
    "pruned": _capi.FLT_ARCHIVE_COUNT_PRUNED,
    "bytes": _capi.FLT_ARCHIVE_COUNT_BYTES,
    "pending_bytes": _capi.FLT_ARCHIVE_COUNT_PENDING_BYTES,
}


class Archive(_Handle):
    """The archive of measured sheets (flatline/record.h): an SQLite file,
    or a PostgreSQL database (``"postgresql://user@host/db"`` or
    ``"pg:host=... dbname=..."``; needs libpq). Attach it to a gauge
    (``Gauge.attach_archive``) and every finished sheet is stored with its
    verdict, coil and height map; while the database is away sheets wait in
    memory (archive_buffer_mb) and are stored when it is back.

    Args:
        location: the SQLite file or the PostgreSQL connection string.
        line: the line's name, stored with every sheet.
        **options: archive_* options (:func:`archive_options`).
    """

    _what = "Archive"

    def __init__(self, location: PathLike, line: str = "", **options: OptionValue) -> None:
        fn = "Archive"
        if not isinstance(line, str):
            raise TypeError(f"{fn}() argument 'line' must be a str, not {type(line).__name__}")
        bag = make_options(fn, options, prefixes=("archive_",))
        super().__init__(_capi.flt_archive_open(_path(fn, location), line, bag))
        self._lock = threading.Lock()

    @property
    def backend(self) -> str:
        """"sqlite" or "postgresql"."""
        return "postgresql" if _capi.flt_archive_backend(self._live()) == 1 else "sqlite"

    def flush(self, timeout_ms: int = 30000) -> None:
        """Waits until every sheet given so far is stored (TimeoutError,
        with the database's last error, after timeout_ms)."""
        self._live().flush_waiting(int(timeout_ms))

    def prune(self) -> int:
        """Applies the retention limits now; the sheets removed."""
        return int(_capi.flt_archive_prune(self._live()))

    def counters(self) -> Dict[str, int]:
        """Sheets given, stored, pending and lost, failed attempts,
        reconnects, sheets pruned, bytes stored and pending."""
        handle = self._live()
        return {name: int(_capi.flt_archive_count(handle, key))
                for name, key in _ARCHIVE_COUNTERS.items()}
