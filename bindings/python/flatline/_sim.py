# SPDX-License-Identifier: Apache-2.0
"""The simulated sensor (flatline/sim.h): a synthetic sheet seen by the two
lasers, as profile rows or as rendered camera frames, with ground truth."""

from __future__ import annotations

import enum
import threading
from typing import Any, Dict, NamedTuple, Optional, Tuple, Union

import numpy as np

from . import capi as _capi
from ._arrays import as_float64, as_index, as_real
from ._calib import Calibration
from ._errors import StateError
from ._options import OptionValue, make_options, options_doc, prefixed_options
from ._pixels import PixelFormat

__all__ = [
    "Defect",
    "SimRows",
    "SimFrame",
    "SimulatedLine",
    "simulator_options",
]


class Defect(enum.IntEnum):
    """Parametric flatness defects for :meth:`SimulatedLine.add_defect`
    (which also takes their names in lower case, e.g. "centre_buckle").

    Each is amplitude_mm * g(x) * sin(2 pi s / period_mm) (the sine is 1 when
    period_mm = 0), with W = sim_strip_width and x in [-W/2, W/2]:
    FLAT g = 0; CENTRE_BUCKLE g = cos^2(pi x / W); WAVY_EDGE_LEFT
    g = max(0, -2x/W)^4; WAVY_EDGE_RIGHT g = max(0, 2x/W)^4; WAVY_EDGE_BOTH
    g = (2x/W)^4; QUARTER_BUCKLE g = exp(-((|x| - W/4) / (W/8))^2); BOW g = 1
    (coil set); CROSSBOW g = (2x/W)^2.
    """

    FLAT = _capi.FLT_SIM_FLAT
    CENTRE_BUCKLE = _capi.FLT_SIM_CENTRE_BUCKLE
    WAVY_EDGE_LEFT = _capi.FLT_SIM_WAVY_EDGE_LEFT
    WAVY_EDGE_RIGHT = _capi.FLT_SIM_WAVY_EDGE_RIGHT
    WAVY_EDGE_BOTH = _capi.FLT_SIM_WAVY_EDGE_BOTH
    QUARTER_BUCKLE = _capi.FLT_SIM_QUARTER_BUCKLE
    BOW = _capi.FLT_SIM_BOW
    CROSSBOW = _capi.FLT_SIM_CROSSBOW


class SimRows(NamedTuple):
    """Profile rows of :meth:`SimulatedLine.next_rows`: n frames, K fibers.
    Exactly what :meth:`Reconstructor.push` and :func:`reconstruct` take."""

    encoder_mm: np.ndarray  #: (n,) each frame's encoder position, mm
    s: np.ndarray  #: (n,) each row's material position, mm (e - mean laser offset)
    height: np.ndarray  #: (n, K) mean of the two lasers' heights, mm
    slope: np.ndarray  #: (n, K) secant slope over the laser spacing, mm/mm
    valid: np.ndarray  #: (n, K) bool, all True (the simulator has no dropouts)
    truth: np.ndarray  #: (n, K) the sheet z(x_k, s), mm: what a perfect gauge reports


class SimFrame(NamedTuple):
    """A rendered camera frame of :meth:`SimulatedLine.next_frame`."""

    image: np.ndarray  #: (height, width) uint8 (Mono8) or uint16 pixels
    encoder_mm: float  #: the frame's encoder position, mm
    s: float  #: material position of the profile row it gives, mm
    truth: np.ndarray  #: (K,) the sheet z(x_k, s), mm
    peak_rows: np.ndarray  #: (2, width) exact line centre per laser and column, px; NaN off-frame


def simulator_options() -> Dict[str, float]:
    """The simulator's options (sim_*) with their C defaults."""
    return {name: info.default for name, info in prefixed_options("sim_").items()}


def _defect(function: str, kind: Any) -> int:
    if isinstance(kind, str):
        name = kind.upper().replace("CENTER", "CENTRE")
        try:
            return int(Defect[name])
        except KeyError:
            names = ", ".join(repr(d.name.lower()) for d in Defect)
            raise ValueError(f"{function}() argument 'kind' = {kind!r} is not one of "
                             f"{names}") from None
    # Any int goes to the library, which names an unknown one.
    return as_index(function, "kind", kind, -2**31, 2**31 - 1)


class SimulatedLine:
    """The simulated sensor: a synthetic sheet passing under the two lasers.

    Args:
        calib: the sensor (a finished :class:`Calibration`; the simulator
            keeps a reference to it), or None for the reference sensor
            (``Calibration.reference()``, 2048 x 2048 px, 1001 fibers at
            2 mm from x = -1000 mm).
        **options: simulator options by their C name (see below): seed,
            frame spacing, vibration, eccentricity, shear transients, peak
            noise, rendering.

    The sheet starts flat; add defects (:meth:`add_defect`) or a height map.
    Frame f is at encoder position sim_start + f * sim_frame_spacing; both
    :meth:`next_rows` and :meth:`next_frame` advance the same frame counter
    and frame f has the same motion in either. Every random draw of frame f
    is seeded by (sim_seed, f): same seed and calls, same bytes.

    A SimulatedLine used from several threads serialises its calls; separate
    instances run in parallel (the GIL is released while generating). Use it
    as a context manager, or call :meth:`close`, to free its frame scratch
    (4 bytes per pixel) deterministically.

    Options:
{options}
    """

    def __init__(self, calib: Optional[Calibration] = None, **options: OptionValue) -> None:
        fn = "SimulatedLine"
        if calib is None:
            calib = Calibration.reference()
        elif not isinstance(calib, Calibration):
            raise TypeError(f"{fn}() argument 'calib' must be a Calibration or None, "
                            f"not {type(calib).__name__}")
        bag = make_options(fn, options, prefixes=("sim_",))
        self._lock = threading.Lock()
        # The C simulator copies the model, but the Python one stays with it:
        # its geometry (fiber_x, offsets) describes this simulator's rows.
        self._calibration = calib
        with calib._reading():
            self._handle: Optional[_capi.flt_sim] = _capi.flt_sim_create(calib._live(), bag)
        self._fibers = int(_capi.flt_sim_fibers(self._handle))
        width, height = _capi.flt_sim_frame_size(self._handle)
        self._frame_size = (int(width), int(height))
        self._format = PixelFormat(_capi.flt_sim_pixel_format(self._handle))
        first, second = calib.laser_offsets
        self._row_offset = 0.5 * (first + second)  # s = e - mean offset

    # -- lifetime -------------------------------------------------------------

    def close(self) -> None:
        """Frees the C simulator now. Idempotent; later calls raise
        StateError."""
        with self._lock:
            self._handle = None

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._handle is None

    def __enter__(self) -> "SimulatedLine":
        self._live()
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def _live(self) -> _capi.flt_sim:
        handle = self._handle
        if handle is None:
            raise StateError("the SimulatedLine is closed")
        return handle

    def __repr__(self) -> str:
        if getattr(self, "_handle", None) is None:  # closed, or __init__ failed
            return "<flatline.SimulatedLine closed>"
        width, height = self._frame_size
        return (f"<flatline.SimulatedLine fibers={self._fibers} frame={width}x{height} "
                f"{self._format.name}>")

    # -- description --------------------------------------------------------------

    @property
    def calibration(self) -> Calibration:
        """The sensor's calibration (the reference sensor when none was given)."""
        return self._calibration

    @property
    def fibers(self) -> int:
        """The number of fibers K (the calibration's grid)."""
        return self._fibers

    @property
    def fiber_x(self) -> np.ndarray:
        """The (K,) fiber positions across the width, mm."""
        return self._calibration.fiber_x

    @property
    def frame_size(self) -> Tuple[int, int]:
        """(width, height) of rendered frames, px."""
        return self._frame_size

    @property
    def pixel_format(self) -> PixelFormat:
        """The pixel format of rendered frames (from sim_bit_depth)."""
        return self._format

    # -- the sheet -------------------------------------------------------------------

    def add_defect(self, kind: Union[Defect, str, int], amplitude_mm: float,
                   period_mm: float = 0.0) -> None:
        """Adds a defect (see :class:`Defect`): amplitude_mm (finite) times
        the defect's shape across the width times sin(2 pi s / period_mm)
        along travel (period_mm >= 0; 0 = constant along travel). Defects add
        up; at most 64 (BufferFullError beyond)."""
        fn = "add_defect"
        kind = _defect(fn, kind)
        amplitude_mm = as_real(fn, "amplitude_mm", amplitude_mm)
        period_mm = as_real(fn, "period_mm", period_mm)
        with self._lock:
            _capi.flt_sim_add_defect(self._live(), kind, amplitude_mm, period_mm)

    def clear_sheet(self) -> None:
        """Removes every defect and the height map: the sheet is flat again."""
        with self._lock:
            _capi.flt_sim_clear_sheet(self._live())

    def set_height_map(self, heights: Any, s0_mm: float, ds_mm: float, x0_mm: float,
                       dx_mm: float) -> None:
        """Adds a height map to the sheet (replacing a previous one):
        heights (rows, cols) mm, row r at s = s0_mm + r * ds_mm along travel,
        column c at x = x0_mm + c * dx_mm across the width (rows, cols >= 2;
        ds, dx > 0; all finite). Interpolated bilinearly, clamped outside.
        Copied."""
        fn = "set_height_map"
        grid = as_float64(fn, "heights", heights, 2)
        values = [as_real(fn, name, v) for name, v in
                  (("s0_mm", s0_mm), ("ds_mm", ds_mm), ("x0_mm", x0_mm), ("dx_mm", dx_mm))]
        with self._lock:
            self._live().set_height_map_array(grid, *values)

    def surface(self, x: Any, s: Any) -> Union[np.ndarray, float]:
        """The ground truth z_sheet(x, s), mm, at points x across the width
        and s along travel (mm). x and s broadcast against each other (e.g.
        ``surface(x[None, :], s[:, None])`` is a (len(s), len(x)) grid); two
        scalars give a float."""
        fn = "surface"
        x_arr = as_float64(fn, "x", x, np.ndim(x))
        s_arr = as_float64(fn, "s", s, np.ndim(s))
        try:
            x_b, s_b = np.broadcast_arrays(x_arr, s_arr)
        except ValueError:
            raise ValueError(f"{fn}() arguments 'x' {x_arr.shape} and 's' {s_arr.shape} "
                             f"do not broadcast") from None
        shape = x_b.shape
        x_flat = np.ascontiguousarray(x_b).reshape(-1)
        s_flat = np.ascontiguousarray(s_b).reshape(-1)
        z = np.empty(x_flat.shape)
        with self._lock:
            self._live().surface_into(x_flat, s_flat, z)
        if not shape:
            return float(z[0])
        return z.reshape(shape)

    # -- output ------------------------------------------------------------------------

    def next_rows(self, n: int) -> SimRows:
        """Generates the next n profile rows (frames f .. f + n - 1), as the
        extractor would produce them but without a camera: per fiber the
        mean of the two lasers' heights and their secant slope, with the
        configured motion and peak noise. Returns :class:`SimRows` of (n,)
        and (n, K) float64 arrays (valid bool). The GIL is released."""
        fn = "next_rows"
        rows = as_index(fn, "n", n)  # 0 is the library's to name
        fibers = self._fibers
        encoder = np.empty(rows)
        s = np.empty(rows)
        height = np.empty((rows, fibers))
        slope = np.empty((rows, fibers))
        valid = np.empty((rows, fibers), dtype=np.uint8)
        truth = np.empty((rows, fibers))
        with self._lock:
            self._live().next_rows_into(encoder, s, height, slope, valid, truth)
        return SimRows(encoder, s, height, slope, valid.view(np.bool_), truth)

    def next_frame(self, out: Optional[np.ndarray] = None) -> SimFrame:
        """Renders the next camera frame through the calibration: both lines
        as Gaussian profiles across rows, speckle, background, shot noise,
        optional reflections, quantised to the pixel format.

        Args:
            out: optional (height, width) C-contiguous array of the pixel
                format's dtype (uint8 for Mono8, else uint16) to render into,
                e.g. the previous frame's image: no allocation then.

        Returns:
            :class:`SimFrame` (image, encoder_mm, s, truth (K,), peak_rows
            (2, width)). The GIL is released while rendering.
        """
        fn = "next_frame"
        width, height = self._frame_size
        dtype = self._format.dtype
        if out is None:
            image = np.empty((height, width), dtype=dtype)
        else:
            image = _frame_buffer(fn, out, dtype, (height, width))
        truth = np.empty(self._fibers)
        peak_rows = np.empty((2, width))
        with self._lock:
            handle = self._live()
            if dtype == np.uint8:
                encoder = handle.next_frame_u8(image, truth, peak_rows)
            else:
                encoder = handle.next_frame_u16(image, truth, peak_rows)
        encoder = float(encoder)
        return SimFrame(image, encoder, encoder - self._row_offset, truth, peak_rows)

    def strip_edges(self, encoder_mm: Any, laser: int = 2
                    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Ground truth of the strip's edges at the encoder positions (n,)
        (or a scalar), under laser 0 or 1, or 2 (the default) for a profile
        row (the mean of both lasers' edges, present only where both see
        the strip). Returns (left_mm, right_mm, present): sensor x of the
        edges (NaN where the laser sees no strip) and a bool array."""
        fn = "strip_edges"
        laser = as_index(fn, "laser", laser, 0, 2)
        scalar = np.ndim(encoder_mm) == 0
        encoder = np.atleast_1d(np.asarray(encoder_mm, dtype=np.float64))
        if encoder.ndim != 1:
            raise ValueError(f"{fn}() argument 'encoder_mm' must be a scalar or have 1 "
                             f"dimension, got shape {encoder.shape}")
        encoder = np.ascontiguousarray(encoder)
        left, right = np.empty(len(encoder)), np.empty(len(encoder))
        present = np.empty(len(encoder), dtype=np.uint8)
        if len(encoder):
            with self._lock:
                self._live().strip_edges_into(laser, encoder, left, right, present)
        if scalar:
            return left[0], right[0], present.view(np.bool_)[0]
        return left, right, present.view(np.bool_)

    def fiber_flags(self, encoder_mm: float) -> np.ndarray:
        """Ground truth of a frame's fiber flags at encoder_mm: what a
        perfect extractor reports (:meth:`Extractor.fiber_flags`), (K,)
        uint8: 0 on the strip for both lasers, FLAG_OFF_STRIP otherwise."""
        fn = "fiber_flags"
        encoder_mm = as_real(fn, "encoder_mm", encoder_mm)
        flags = np.empty(self._fibers, dtype=np.uint8)
        with self._lock:
            self._live().fiber_flags_into(encoder_mm, flags)
        return flags

    def rewind(self) -> None:
        """Back to frame 0: the following output repeats the first exactly."""
        with self._lock:
            _capi.flt_sim_rewind(self._live())


def _frame_buffer(function: str, out: Any, dtype: np.dtype,
                  shape: Tuple[int, int]) -> np.ndarray:
    if not isinstance(out, np.ndarray):
        raise TypeError(f"{function}() argument 'out' must be a numpy array, not "
                        f"{type(out).__name__}")
    if out.dtype != dtype:  # also refuses the non-native byte order
        raise TypeError(f"{function}() argument 'out' has dtype {out.dtype}, but the "
                        f"pixel format needs {dtype}")
    if out.shape != shape:
        raise ValueError(f"{function}() argument 'out' has shape {out.shape}, but the "
                         f"frame size requires {shape}")
    if not (out.flags.c_contiguous and out.flags.aligned and out.flags.writeable):
        raise ValueError(f"{function}() argument 'out' must be C-contiguous, aligned "
                         f"and writeable")
    return out


def _document_options() -> None:
    text = options_doc(simulator_options())
    if SimulatedLine.__doc__:
        SimulatedLine.__doc__ = SimulatedLine.__doc__.replace("{options}", text)


_document_options()
