# SPDX-License-Identifier: Apache-2.0
"""The streaming Hermite reconstructor (flatline/recon.h)."""

from __future__ import annotations

import threading
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np

from . import capi as _capi
from ._arrays import as_float64, block, check_shape
from ._calib import Calibration
from ._errors import InvalidArgumentError, NotFoundError, StateError
from ._options import OptionValue, make_options, option_info, options

__all__ = [
    "FLAG_INVALID_INPUT",
    "FLAG_GAP",
    "FLAG_NO_DATA",
    "FLAG_OFF_STRIP",
    "Reconstructor",
    "reconstruct",
    "reconstruct_flagged",
    "reconstructor_options",
]

#: This row's own sample of the fiber was invalid; the value is bridged.
FLAG_INVALID_INPUT: int = _capi.FLT_FLAG_INVALID_INPUT
#: The row lies in a run of invalid samples longer than max_gap: the value
#: comes from the smoothness prior alone.
FLAG_GAP: int = _capi.FLT_FLAG_GAP
#: The fiber has had no valid height since the strip began: z is NaN.
FLAG_NO_DATA: int = _capi.FLT_FLAG_NO_DATA
#: The fiber lies off the strip in this row (beyond its edges, or no strip
#: under a laser): not invalid data, nothing to measure. As input (the
#: extractor's :meth:`Extractor.fiber_flags`) the sample is not used; as
#: output the value is NaN with this bit alone: never reconstructed as strip.
FLAG_OFF_STRIP: int = _capi.FLT_FLAG_OFF_STRIP


def _flags(function: str, value: Any, shape: Tuple[int, ...]) -> np.ndarray:
    """The extractor's per-sample FLAG_* bits as a C-contiguous uint8 array
    of `shape`: an integer array with values 0..255."""
    array = np.asarray(value)
    if array.dtype.kind not in "iu":
        raise TypeError(f"{function}() argument 'flags' must be an integer array of FLAG_* "
                        f"bits (the extractor's uint8 flags), got dtype {array.dtype}")
    if array.shape != shape:
        raise ValueError(f"{function}() argument 'flags' has shape {array.shape}, but "
                         f"height.shape requires {shape}")
    if array.size and (array.min() < 0 or array.max() > 255):
        raise ValueError(f"{function}() argument 'flags' holds values outside 0..255 "
                         f"(FLAG_* bits)")
    return np.ascontiguousarray(array, dtype=np.uint8)


def reconstructor_options() -> Dict[str, float]:
    """The options the reconstructor reads, with their defaults (as resolved
    by the library: knot_spacing 0 reads as laser_spacing). Asked of the
    library, so options added to it appear here without a binding change."""
    probe = _capi.flt_recon_create(1, None)
    names: Dict[str, float] = {}
    for info in options().values():
        try:
            names[info.name] = _capi.flt_recon_get_option(probe, info.key)
        except InvalidArgumentError:  # another component's
            pass
    return names


_NAMES = frozenset(reconstructor_options())


def reconstruct(s: Any, height: Any, slope: Any, valid: Any = None,
                **options: OptionValue) -> np.ndarray:
    """Reconstructs one whole sheet: the least-squares Hermite spline of every
    fiber, fitted to all rows at once (no lag, no carry-over).

    Args:
        s: (N,) material position of each row along travel, mm, strictly
            increasing (the true encoder positions; any spacing).
        height: (N, K) measured heights, mm: per row and fiber, the mean of
            the two lasers' heights, (z(s - d/2) + z(s + d/2)) / 2.
        slope: (N, K) measured slopes, mm/mm: (z(s + d/2) - z(s - d/2)) / d,
            d = laser_spacing.
        valid: (N, K) bool mask (True = valid) or None. NaN heights or slopes
            are treated as invalid too.
        **options: reconstructor options by their C name (see below).

    Returns:
        z: (N, K) float64, reconstructed height at each row and fiber, mm;
        NaN only where a fiber has no valid height at all.

    Raises:
        TypeError: an argument of a dtype that cannot be cast safely to
            float64, or an unknown option name.
        ValueError: a wrong number of dimensions or a wrong shape.
        InvalidArgumentError (a ValueError): rejected by the library, e.g.
            s not strictly increasing or an option out of range.

    The GIL is released while the library computes.

    Options:
{options}
    """
    z, _flags = reconstruct_with_flags(s, height, slope, valid, **options)
    return z


def release_reconstruct_memory() -> float:
    """Frees the working memory :func:`reconstruct` (and its variants) keep
    for the next call of a sheet of the same shape: a loop of calls
    allocates nothing after the first, and up to 4 shapes and 256 MB stay
    kept until this call or the end of the process. For after a one-off
    sheet much larger than the usual ones, or before a long idle time.
    Returns the bytes freed (as recon.h's "Memory" formula counts them)."""
    return float(_capi.flt_reconstruct_release())


def reconstruct_flagged(s: Any, height: Any, slope: Any, flags: Any,
                        **options: OptionValue) -> Tuple[np.ndarray, np.ndarray]:
    """As :func:`reconstruct_with_flags`, with the extractor's per-sample
    FLAG_* bits (N, K) in place of a validity mask: 0 valid,
    FLAG_INVALID_INPUT invalid (bridged), FLAG_OFF_STRIP off the strip (not
    used; its output is NaN flagged FLAG_OFF_STRIP alone). Returns (z,
    flags), both (N, K)."""
    fn = "reconstruct_flagged"
    s, height, slope, _mask, _masked = block(fn, s, height, slope, None)
    bits = _flags(fn, flags, height.shape)
    bag = make_options(fn, options, names=_NAMES)
    z = np.empty(height.shape, dtype=np.float64)
    out = np.empty(height.shape, dtype=np.uint8)
    _capi.flt_py_reconstruct(bag, s, height, slope, bits, 2, z, out)
    return z, out


def reconstruct_with_flags(s: Any, height: Any, slope: Any, valid: Any = None,
                           **options: OptionValue) -> Tuple[np.ndarray, np.ndarray]:
    """As :func:`reconstruct`, and also returns the (N, K) uint8 flags
    (FLAG_* bits) of every output value."""
    fn = "reconstruct"
    s, height, slope, mask, masked = block(fn, s, height, slope, valid)
    bag = make_options(fn, options, names=_NAMES)
    z = np.empty(height.shape, dtype=np.float64)
    flags = np.empty(height.shape, dtype=np.uint8)
    _capi.flt_py_reconstruct(bag, s, height, slope, mask, masked, z, flags)
    return z, flags


class Reconstructor:
    """A streaming reconstructor for a fixed number of fibers.

    Rows (one camera frame each, at material position s along travel) go in
    with :meth:`push`; finished rows come out with :meth:`pull`, at most
    latency_mm of travel later (twice that at a strip's head); :meth:`peek`
    gives the rows not finished yet, provisionally. :meth:`end_sheet`
    finishes every pushed row and carries the last knot's height and slope
    into the next sheet, so consecutive sheets join smoothly; :meth:`reset`
    starts a new strip.

    Args:
        fibers: a finished :class:`Calibration`, the way to create one for a
            real sensor: the fiber count is its fiber grid's and the laser
            spacing the distance between its lasers (laser_spacing must then
            be left out, or equal it: a disagreement raises
            InvalidArgumentError). Or the number of fibers K (>= 1), for
            lasers laser_spacing mm apart (default 100 mm, the reference
            sensor's).
        **options: reconstructor options by their C name (see below).

    Use it as a context manager, or call :meth:`close`, to free the C
    buffers (9 bytes per row and fiber of row_capacity, 17 in robust mode;
    recon.h, "Memory") deterministically.
    One instance may be used from several threads; its calls are then
    serialised. Separate instances run in parallel (the GIL is released in
    push, pull and end_sheet).

    Options:
{options}
    """

    def __init__(self, fibers: Union[int, Calibration], **options: OptionValue) -> None:
        fn = "Reconstructor"
        if isinstance(fibers, Calibration):
            bag = make_options(fn, options, names=_NAMES)
            with fibers._reading():
                handle = _capi.flt_recon_create_from_calib(fibers._live(), bag)
        else:
            if isinstance(fibers, bool) or not isinstance(fibers, (int, np.integer)):
                raise TypeError(
                    f"{fn}() argument 'fibers' must be an int or a Calibration, "
                    f"not {type(fibers).__name__}"
                )
            if fibers < 1:
                raise ValueError(f"{fn}() argument 'fibers' must be >= 1, got {fibers}")
            bag = make_options(fn, options, names=_NAMES)
            handle = _capi.flt_recon_create(int(fibers), bag)
        self._lock = threading.Lock()
        self._handle: Optional[_capi.flt_recon] = handle
        self._fibers = int(_capi.flt_recon_fibers(self._handle))

    # -- lifetime ----------------------------------------------------------

    def close(self) -> None:
        """Frees the C reconstructor now, even while a traceback or another
        object still refers to this Reconstructor. Idempotent; any later
        call other than close raises StateError."""
        with self._lock:
            handle, self._handle = self._handle, None
            _capi.flt_py_release(handle)

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._handle is None

    def __enter__(self) -> "Reconstructor":
        self._live()
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def _live(self) -> _capi.flt_recon:
        handle = self._handle
        if handle is None:
            raise StateError("the Reconstructor is closed")
        return handle

    def __repr__(self) -> str:
        if self._handle is None:
            return "<flatline.Reconstructor closed>"
        return (f"<flatline.Reconstructor fibers={self._fibers} "
                f"ready={self.ready}>")

    # -- properties ----------------------------------------------------------

    @property
    def fibers(self) -> int:
        """The number of fibers K."""
        return self._fibers

    @property
    def ready(self) -> int:
        """The number of finished rows waiting to be pulled."""
        with self._lock:
            return int(_capi.flt_recon_ready(self._live()))

    def option(self, name: str) -> float:
        """The effective value of option `name` (knot_spacing resolved to mm).
        NotFoundError (a KeyError) if the library has no such option,
        InvalidArgumentError (a ValueError) if it is another component's."""
        key = option_info(name).key
        with self._lock:
            return float(_capi.flt_recon_get_option(self._live(), key))

    # -- streaming -----------------------------------------------------------

    def push(self, s: Any, height: Any, slope: Any, valid: Any = None) -> None:
        """Pushes one row or a block of rows.

        One row: s a scalar (mm), height and slope (K,), valid (K,) or None.
        A block: s (n,), height and slope (n, K), valid (n, K) or None.

        s is the material position along travel in mm, strictly increasing
        across calls and sheets; height in mm and slope in mm/mm as measured
        by the two lasers (see :func:`reconstruct`). valid is a bool mask
        (True = valid); NaN samples are invalid too. On any error nothing is
        pushed. BufferFullError when the rows do not fit in row_capacity:
        pull first, or push smaller blocks.
        """
        fn = "push"
        if np.ndim(height) == 1:  # one row
            if np.ndim(s) != 0:
                raise ValueError(
                    f"{fn}() argument 's' must be a scalar when 'height' is one "
                    f"row of shape (K,); got shape {np.shape(s)}"
                )
            s = np.reshape(as_float64(fn, "s", s, 0), (1,))
            height = np.reshape(as_float64(fn, "height", height, 1), (1, -1))
            slope = np.reshape(as_float64(fn, "slope", slope, 1), (1, -1))
            if valid is not None:
                valid = np.reshape(np.asarray(valid), (1, -1))
        s, height, slope, mask, masked = block(fn, s, height, slope, valid)
        check_shape(fn, "height", height, (height.shape[0], self._fibers),
                    f"a Reconstructor of {self._fibers} fibers")
        with self._lock:
            self._live().push_block(s, height, slope, mask, masked)

    def push_flagged(self, s: Any, height: Any, slope: Any, flags: Any) -> None:
        """Pushes one row or a block of rows with the extractor's per-fiber
        FLAG_* bits (:meth:`Extractor.fiber_flags`) in place of a validity
        mask: 0 valid, FLAG_INVALID_INPUT invalid (bridged), FLAG_OFF_STRIP
        off the strip (not used; its rows come out NaN flagged
        FLAG_OFF_STRIP, so a strip that wanders, narrows or ends is never
        extended beyond its edges). Shapes as :meth:`push` (flags like
        height). On any error nothing is pushed."""
        fn = "push_flagged"
        if np.ndim(height) == 1:  # one row
            if np.ndim(s) != 0:
                raise ValueError(
                    f"{fn}() argument 's' must be a scalar when 'height' is one "
                    f"row of shape (K,); got shape {np.shape(s)}"
                )
            s = np.reshape(as_float64(fn, "s", s, 0), (1,))
            height = np.reshape(as_float64(fn, "height", height, 1), (1, -1))
            slope = np.reshape(as_float64(fn, "slope", slope, 1), (1, -1))
            flags = np.reshape(np.asarray(flags), (1, -1))
        s, height, slope, _mask, _masked = block(fn, s, height, slope, None)
        check_shape(fn, "height", height, (height.shape[0], self._fibers),
                    f"a Reconstructor of {self._fibers} fibers")
        bits = _flags(fn, flags, height.shape)
        with self._lock:
            self._live().push_block(s, height, slope, bits, 2)

    def pull(self, max_rows: Optional[int] = None
             ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pulls the finished rows (at most max_rows), oldest first.

        Returns:
            (s, z, flags): s (n,) positions in mm; z (n, K) reconstructed
            heights in mm (NaN only where FLAG_NO_DATA is set); flags (n, K)
            uint8 FLAG_* bits. n may be 0.

        Raises StateError if nothing was pushed since creation or reset.
        """
        with self._lock:
            handle = self._live()
            rows = int(_capi.flt_recon_ready(handle))
            if max_rows is not None:
                if max_rows < 0:
                    raise ValueError(f"pull() argument 'max_rows' must be >= 0, got {max_rows}")
                rows = min(rows, int(max_rows))
            s = np.empty(rows, dtype=np.float64)
            z = np.empty((rows, self._fibers), dtype=np.float64)
            flags = np.empty((rows, self._fibers), dtype=np.uint8)
            got = int(handle.pull_into(s, z, flags))
        if got != rows:  # only if the library disagrees with its ready count
            s, z, flags = s[:got], z[:got], flags[:got]
        return s, z, flags

    @property
    def pending(self) -> int:
        """The number of rows pushed and not finished yet (see :meth:`peek`)."""
        with self._lock:
            return int(_capi.flt_recon_pending(self._live()))

    def peek(self, max_rows: Optional[int] = None
             ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The rows pushed and not finished yet, as the reconstructor
        estimates them now (at most max_rows, oldest first): provisional
        values, given every row pushed so far. They are final only when
        :meth:`pull` returns them, latency_mm of strip later; an early answer
        (a sheet's provisional verdict at its cut) can be computed from them
        and replaced by the final one. Finished rows not pulled yet are
        skipped (pull them first); nothing :meth:`pull` returns changes.

        Returns:
            (s, z, flags) as :meth:`pull`: s (n,) mm, z (n, K) mm (NaN only
            with FLAG_NO_DATA or FLAG_OFF_STRIP), flags (n, K) uint8.

        Raises StateError if nothing was pushed since creation or reset.
        """
        with self._lock:
            handle = self._live()
            rows = int(_capi.flt_recon_pending(handle))
            if max_rows is not None:
                if max_rows < 0:
                    raise ValueError(f"peek() argument 'max_rows' must be >= 0, got {max_rows}")
                rows = min(rows, int(max_rows))
            s = np.empty(rows, dtype=np.float64)
            z = np.empty((rows, self._fibers), dtype=np.float64)
            flags = np.empty((rows, self._fibers), dtype=np.uint8)
            got = int(handle.peek_into(s, z, flags))
        if got != rows:
            s, z, flags = s[:got], z[:got], flags[:got]
        return s, z, flags

    def end_sheet(self) -> None:
        """Finishes the sheet: every pushed row becomes ready to pull, and the
        last emitted knot is carried into the next sheet as a hard boundary
        condition. StateError if no row was pushed since the last end_sheet,
        creation or reset."""
        with self._lock:
            self._live().finish_sheet()

    def reset(self) -> None:
        """Starts a new strip: drops every row not pulled and the carry-over."""
        with self._lock:
            _capi.flt_recon_reset(self._live())

    def boundary(self) -> Tuple[float, np.ndarray, np.ndarray]:
        """The boundary condition carried into the next sheet.

        Returns:
            (s, height, slope): the knot position in mm, and per fiber (K,)
            the height in mm and slope in mm/mm there.

        StateError before the first end_sheet of a strip.
        """
        height = np.empty(self._fibers, dtype=np.float64)
        slope = np.empty(self._fibers, dtype=np.float64)
        with self._lock:
            s = self._live().boundary_into(height, slope)
        return float(s), height, slope


def _document_options() -> None:
    from ._options import options_doc

    text = options_doc(reconstructor_options())
    for target in (reconstruct, Reconstructor):
        if target.__doc__:
            target.__doc__ = target.__doc__.replace("{options}", text)


_document_options()
