# SPDX-License-Identifier: Apache-2.0
"""The frame-to-profile extractor (flatline/extractor.h): one camera frame
in, one profile row (height, slope, validity per fiber) out."""

from __future__ import annotations

import threading
from typing import Any, Dict, NamedTuple, Optional, Tuple, Union

import numpy as np

from . import capi as _capi
from ._arrays import as_index, as_real
from ._calib import LASERS, Calibration
from ._errors import StateError
from ._options import OptionValue, make_options, options_doc, prefixed_options
from ._pixels import PixelFormat, check_one_channel

__all__ = ["ExtractedRow", "Extractor", "Saturation", "StripEdges", "STRIP_LEFT_OPEN", "STRIP_NONE",
           "STRIP_RIGHT_OPEN", "STRIP_LEFT_GLINT", "STRIP_RIGHT_GLINT", "extractor_options"]

#: No strip under the laser (a head or tail between coils, or no line): both
#: edges, the width and the centre are NaN (the open bits are set too).
STRIP_NONE: int = _capi.FLT_STRIP_NONE
#: The strip reaches the frame's border at low sensor x: left_mm is NaN.
STRIP_LEFT_OPEN: int = _capi.FLT_STRIP_LEFT_OPEN
#: The same at high sensor x: right_mm is NaN.
STRIP_RIGHT_OPEN: int = _capi.FLT_STRIP_RIGHT_OPEN
#: A glint lay on the edge at low sensor x, which pushes a measured edge
#: outward. One laser: its own edge had it (the value is the other laser's
#: where that one was clean); the row (laser 2): both had it, and left_mm may
#: lie up to about 1.5 mm outward.
STRIP_LEFT_GLINT: int = _capi.FLT_STRIP_LEFT_GLINT
#: The same at high sensor x.
STRIP_RIGHT_GLINT: int = _capi.FLT_STRIP_RIGHT_GLINT


class ExtractedRow(NamedTuple):
    """One profile row from :meth:`Extractor.process`: exactly what
    :meth:`Reconstructor.push` takes (s scalar, arrays (K,))."""

    s: float  #: the row's material position, mm: encoder_mm - mean laser offset
    height: np.ndarray  #: (K,) mean of the two lasers' z, mm; NaN where invalid
    slope: np.ndarray  #: (K,) (z_ahead - z_behind) / laser spacing, mm/mm; NaN where invalid
    valid: np.ndarray  #: (K,) bool: both lasers gave a z for this fiber


class StripEdges(NamedTuple):
    """Where the last frame shows the strip (:meth:`Extractor.strip`), sensor
    x in mm; a value is NaN exactly where ``flags`` says why."""

    left_mm: float  #: the edge at low sensor x (NaN with STRIP_LEFT_OPEN)
    right_mm: float  #: the edge at high sensor x (NaN with STRIP_RIGHT_OPEN)
    width_mm: float  #: right - left, NaN unless both edges are seen
    centre_mm: float  #: (left + right) / 2, NaN unless both edges are seen
    flags: int  #: STRIP_* bits


class Saturation(NamedTuple):
    """The last frame's saturated peaks (:meth:`Extractor.saturation`): the
    strip's columns with a valid peak, how many of them were saturated
    (measured as a plateau), and their share, for an exposure controller."""

    peaks: int  #: the strip's columns with a valid peak
    saturated: int  #: of those, the saturated ones
    fraction: float  #: saturated / peaks, 0 without a peak


def extractor_options() -> Dict[str, float]:
    """The extractor's options (extract_*) with their C defaults."""
    return {name: info.default for name, info in prefixed_options("extract_").items()}


def _format(function: str, value: Any) -> Optional[PixelFormat]:
    if value is None:
        return None
    if isinstance(value, str):
        try:
            return PixelFormat[value.upper()]
        except KeyError:
            names = ", ".join(repr(p.name.lower()) for p in PixelFormat)
            raise ValueError(f"{function}() argument 'pixel_format' = {value!r} is not "
                             f"one of {names}") from None
    bits = as_index(function, "pixel_format", value)
    try:
        return PixelFormat(bits)
    except ValueError:
        raise ValueError(f"{function}() argument 'pixel_format' = {bits} is not 8, 10, "
                         f"12 or 16") from None


class Extractor:
    """Turns camera frames into profile rows, for a finished calibration.

    Per column and laser it finds the strongest valid peak in the laser's
    band of rows, refines it to sub-pixel accuracy (zero crossing of a
    Savitzky-Golay derivative), undistorts and maps it onto the laser plane,
    resamples both lasers onto the fiber grid and combines them into height
    and slope. A fiber is valid only when both lasers see it.

    Args:
        calib: a finished :class:`Calibration` (the extractor keeps a
            reference; the C extractor copies it).
        pixel_format: the frames' format (:class:`PixelFormat`, its name or
            its bits). None (the default): Mono8 for uint8 frames, Mono16 for
            uint16 frames. Give it for 10- and 12-bit cameras: the peak
            thresholds are fractions of the format's full scale.
        **options: extractor options by their C name (see below). Bands
            default to automatic (found in the first frame).

    Frames: 2-D numpy arrays (height, width) of the calibration's frame size,
    uint8 or uint16. Arrays whose rows are contiguous (C order, or a row
    slice / ROI view of a bigger buffer) go to C without a copy; others are
    copied once. Any other dtype is a TypeError, a wrong shape a ValueError.

    One Extractor serialises its calls; separate ones run in parallel (the
    GIL is released in :meth:`process`). Use it as a context manager or call
    :meth:`close` to free its tables deterministically.

    Options:
{options}
    """

    def __init__(self, calib: Calibration, pixel_format: Union[PixelFormat, str, int, None] = None,
                 **options: OptionValue) -> None:
        fn = "Extractor"
        if not isinstance(calib, Calibration):
            raise TypeError(f"{fn}() argument 'calib' must be a Calibration, not "
                            f"{type(calib).__name__}")
        self._format = _format(fn, pixel_format)
        bag = make_options(fn, options, prefixes=("extract_",))
        self._lock = threading.Lock()
        self._calibration = calib
        with calib._reading():
            self._handle: Optional[_capi.flt_extractor] = _capi.flt_extractor_create(
                calib._live(), bag)
        self._fibers = int(_capi.flt_extractor_fibers(self._handle))
        self._frame_size = calib.frame_size

    # -- lifetime ---------------------------------------------------------------

    def close(self) -> None:
        """Frees the C extractor now, even while a traceback or another
        object still refers to this Extractor. Idempotent; later calls raise
        StateError."""
        with self._lock:
            handle, self._handle = self._handle, None
            _capi.flt_py_release(handle)

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._handle is None

    def __enter__(self) -> "Extractor":
        self._live()
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def _live(self) -> _capi.flt_extractor:
        handle = self._handle
        if handle is None:
            raise StateError("the Extractor is closed")
        return handle

    def __repr__(self) -> str:
        if getattr(self, "_handle", None) is None:  # closed, or __init__ failed
            return "<flatline.Extractor closed>"
        width, height = self._frame_size
        return f"<flatline.Extractor fibers={self._fibers} frame={width}x{height}>"

    # -- description ----------------------------------------------------------------

    @property
    def calibration(self) -> Calibration:
        """The calibration the extractor was built from."""
        return self._calibration

    @property
    def fibers(self) -> int:
        """The number of fibers K of a row (the calibration's fiber count)."""
        return self._fibers

    @property
    def frame_size(self) -> Tuple[int, int]:
        """(width, height) of the frames it takes, px."""
        return self._frame_size

    @property
    def pixel_format(self) -> Optional[PixelFormat]:
        """The configured pixel format (None: from each frame's dtype)."""
        return self._format

    def band(self, laser: int) -> Tuple[int, int]:
        """Laser `laser`'s band of rows: (first_row, rows), px. StateError
        while an automatic band waits for its first frame."""
        laser = as_index("band", "laser", laser, 0, LASERS - 1)
        with self._lock:
            first, rows = _capi.flt_extractor_band(self._live(), laser)
        return int(first), int(rows)

    # -- frames ------------------------------------------------------------------

    def _frame(self, function: str, frame: Any) -> Tuple[np.ndarray, int]:
        """The frame as an array C can read, and its pixel format's bits."""
        if not isinstance(frame, np.ndarray):
            raise TypeError(f"{function}() argument 'frame' must be a numpy array, not "
                            f"{type(frame).__name__}")
        if frame.dtype.kind != "u" or frame.dtype.itemsize not in (1, 2):
            raise TypeError(f"{function}() argument 'frame' has dtype {frame.dtype}; "
                            f"frames are uint8 (Mono8) or uint16 (Mono10/12/16)")
        fmt = self._format
        if fmt is None:
            fmt = PixelFormat.MONO8 if frame.dtype.itemsize == 1 else PixelFormat.MONO16
        elif fmt.dtype.itemsize != frame.dtype.itemsize:
            raise TypeError(f"{function}() argument 'frame' has dtype {frame.dtype}, but "
                            f"the extractor's pixel format {fmt.name} needs {fmt.dtype}")
        check_one_channel(function, frame)
        width, height = self._frame_size
        if frame.shape != (height, width):
            raise ValueError(f"{function}() argument 'frame' has shape {frame.shape}, but "
                             f"the calibration's frames are {(height, width)} "
                             f"(height, width)")
        item = frame.dtype.itemsize
        if not (frame.flags.aligned and frame.dtype.isnative and frame.strides[1] == item
                and frame.strides[0] >= width * item):
            # Rows not contiguous (Fortran order, a column slice, reversed) or
            # swapped bytes: one copy the library can read.
            frame = np.ascontiguousarray(frame, dtype=frame.dtype.newbyteorder("="))
        return frame, int(fmt)

    def process(self, frame: np.ndarray, encoder_mm: float) -> ExtractedRow:
        """Turns one frame into one profile row.

        Args:
            frame: (height, width) uint8 or uint16 pixels.
            encoder_mm: the frame's encoder position, mm (finite).

        Returns:
            :class:`ExtractedRow` (s, height (K,), slope (K,), valid (K,)):
            heights and slopes are NaN where a fiber is invalid.

        A bad frame raises TypeError / ValueError and leaves the extractor
        usable. The GIL is released while it works.
        """
        fn = "process"
        pixels, bits = self._frame(fn, frame)
        encoder_mm = as_real(fn, "encoder_mm", encoder_mm)
        height = np.empty(self._fibers)
        slope = np.empty(self._fibers)
        valid = np.empty(self._fibers, dtype=np.uint8)
        with self._lock:
            s = self._live().process_frame(pixels, bits, encoder_mm, height, slope, valid)
        return ExtractedRow(float(s), height, slope, valid.view(np.bool_))

    def peaks(self, frame: Optional[np.ndarray] = None) -> np.ndarray:
        """The sub-pixel peak row of every column and laser, (2, width)
        float64 px (raw image rows), NaN where a column has no valid peak.

        With a frame, processes it first (as :meth:`process` at encoder 0;
        the row is discarded); without one, reports the last processed
        frame (StateError before the first)."""
        if frame is not None:
            self.process(frame, 0.0)
        width = self._frame_size[0]
        rows = np.empty((2, width))
        with self._lock:
            self._live().peaks_into(rows)
        return rows

    def fiber_flags(self) -> np.ndarray:
        """The last processed frame's flags per fiber, (K,) uint8: 0 valid,
        FLAG_OFF_STRIP for a fiber off the strip (beyond its edges, or no
        strip under a laser), FLAG_INVALID_INPUT for a fiber on the strip
        without a valid z from both lasers. Exactly what
        :meth:`Reconstructor.push_flagged` takes. StateError before the
        first frame."""
        flags = np.empty(self._fibers, dtype=np.uint8)
        with self._lock:
            self._live().fiber_flags_into(flags)
        return flags

    def strip(self, laser: int = 2) -> StripEdges:
        """Where the last processed frame shows the strip: its edges, width
        and centre in sensor x (mm) under laser 0 or 1, or 2 (the default)
        for the profile row (the mean of both lasers' edges, an edge seen
        only where both see it). StateError before the first frame."""
        laser = as_index("strip", "laser", laser, 0, 2)
        out = np.empty(5)
        with self._lock:
            self._live().strip_into(laser, out)
        return StripEdges(float(out[0]), float(out[1]), float(out[2]), float(out[3]),
                          int(out[4]))

    def saturation(self, laser: int = 2) -> Saturation:
        """The last processed frame's saturated peaks on the strip, under
        laser 0 or 1, or 2 (the default) for both. StateError before the
        first frame."""
        laser = as_index("saturation", "laser", laser, 0, 2)
        out = np.empty(3)
        with self._lock:
            self._live().saturation_into(laser, out)
        return Saturation(int(out[0]), int(out[1]), float(out[2]))

    def laser_profiles(self) -> np.ndarray:
        """Each laser's z on the fiber grid for the last processed frame,
        (2, K) mm, NaN where invalid. Laser L's reading is at material
        s = encoder_mm - offset_L. StateError before the first frame."""
        z = np.empty((2, self._fibers))
        with self._lock:
            self._live().laser_profiles_into(z)
        return z


def _document_options() -> None:
    text = options_doc(extractor_options())
    if Extractor.__doc__:
        Extractor.__doc__ = Extractor.__doc__.replace("{options}", text)


_document_options()
