# SPDX-License-Identifier: Apache-2.0
"""The calibration model (flatline/calib.h): camera intrinsics and lens
distortion, one homography per laser plane, and the sensor geometry."""

from __future__ import annotations

import contextlib
import dataclasses
import enum
import math
import os
import threading
from typing import Any, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import capi as _capi
from ._arrays import as_float64, as_index, as_points, as_real
from ._errors import StateError
from ._options import OptionValue, make_options

__all__ = [
    "LASERS",
    "Target",
    "Intrinsics",
    "FiberGrid",
    "IntrinsicsFit",
    "HomographyFit",
    "Calibration",
]

#: Number of lasers (and laser planes) of the sensor, numbered 0 and 1.
LASERS: int = _capi.FLT_CALIB_LASERS

# (A runtime alias, not a string: forward references would resolve in the
# importing module, which need not import os.)
PathLike = Union[str, bytes, os.PathLike]


class Target(enum.IntEnum):
    """Calibration target kinds for :meth:`Calibration.estimate_intrinsics`
    (``pattern=`` also takes their names in lower case)."""

    #: Chessboard; columns x rows counts the *inner* corners.
    CHESSBOARD = _capi.FLT_TARGET_CHESSBOARD
    #: Symmetric grid of dark circles on white; columns x rows circles.
    CIRCLE_GRID = _capi.FLT_TARGET_CIRCLE_GRID
    #: Asymmetric circle grid (OpenCV's layout); pitch is the distance between
    #: neighbouring circles of one row divided by two.
    ASYMMETRIC_CIRCLE_GRID = _capi.FLT_TARGET_ASYMMETRIC_CIRCLE_GRID


_DISTORTION_NAMES = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")  # OpenCV order


@dataclasses.dataclass(frozen=True)
class Intrinsics:
    """Camera intrinsics and lens distortion in OpenCV's pinhole model.

    fx, fy: focal lengths, px (> 0). cx, cy: principal point, px (image
    frame: u right, v down, origin at the centre of the top-left pixel).
    k1..k6: radial distortion (k4..k6 the rational terms, 0 unless
    estimated with rational_distortion); p1, p2: tangential distortion.
    All dimensionless except the px of the first four.

    ``Intrinsics(**d)`` takes a dict with these keys (the distortion keys
    default to 0); :meth:`as_dict` gives one back.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    k3: float = 0.0
    k4: float = 0.0
    k5: float = 0.0
    k6: float = 0.0

    @property
    def camera_matrix(self) -> np.ndarray:
        """The 3x3 camera matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], px."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy],
                         [0.0, 0.0, 1.0]])

    @property
    def distortion(self) -> np.ndarray:
        """The (8,) distortion coefficients in OpenCV's order
        k1, k2, p1, p2, k3, k4, k5, k6 (what cv2 functions take)."""
        return np.array([getattr(self, name) for name in _DISTORTION_NAMES])

    def as_dict(self) -> dict:
        """The twelve values by name."""
        return dataclasses.asdict(self)

    @classmethod
    def from_arrays(cls, camera: Any, distortion: Any = None) -> "Intrinsics":
        """From a camera matrix (3x3) or (fx, fy, cx, cy), and up to 8
        distortion coefficients in OpenCV's order (missing ones are 0)."""
        fn = "Intrinsics.from_arrays"
        cam = np.asarray(camera, dtype=np.float64)
        if cam.shape == (3, 3):
            values = [cam[0, 0], cam[1, 1], cam[0, 2], cam[1, 2]]
        elif cam.shape == (4,):
            values = list(cam)
        else:
            raise ValueError(f"{fn}() argument 'camera' must have shape (3, 3) or (4,), "
                             f"got {cam.shape}")
        coeffs = np.zeros(8)
        if distortion is not None:
            given = np.asarray(distortion, dtype=np.float64).ravel()
            if given.size > 8:
                raise ValueError(f"{fn}() argument 'distortion' has {given.size} "
                                 f"coefficients; at most 8 (k1 k2 p1 p2 k3 k4 k5 k6)")
            coeffs[:given.size] = given
        return cls(*(float(v) for v in values), *(float(v) for v in coeffs))


class FiberGrid(NamedTuple):
    """The fiber grid: fiber k sits at x = first_x_mm + k * pitch_mm across
    the width, k < count."""

    first_x_mm: float
    pitch_mm: float
    count: int

    @property
    def x(self) -> np.ndarray:
        """The (count,) fiber positions across the width, mm."""
        return self.first_x_mm + self.pitch_mm * np.arange(self.count, dtype=np.float64)


class IntrinsicsFit(NamedTuple):
    """What :meth:`Calibration.estimate_intrinsics` reports."""

    rms_px: float  #: overall RMS reprojection error, px
    view_rms_px: np.ndarray  #: (views,) each view's RMS, px; NaN where no target was found
    intrinsics: Intrinsics  #: the estimate, now stored in the model


class HomographyFit(NamedTuple):
    """What :meth:`Calibration.estimate_homography` reports."""

    rms_px: float  #: RMS image residual over the inliers, px
    rms_mm: float  #: RMS plane residual over the inliers, mm
    residual_px: np.ndarray  #: (N,) image-side distance of each point, px
    residual_mm: np.ndarray  #: (N,) plane-side distance of each point, mm
    inliers: np.ndarray  #: (N,) bool, True where the point was used in the final fit
    homography: np.ndarray  #: (3, 3) the estimate, now stored in the model


def _path(function: str, path: Any) -> str:
    try:
        text = os.fsdecode(os.fspath(path))
    except TypeError:
        raise TypeError(f"{function}() argument 'path' must be a str, bytes or "
                        f"os.PathLike, not {type(path).__name__}") from None
    if "\0" in text:
        raise ValueError(f"{function}() argument 'path' contains a NUL character")
    return text


def _laser(function: str, laser: Any) -> int:
    return as_index(function, "laser", laser, 0, LASERS - 1)


def _target(function: str, pattern: Any) -> int:
    if isinstance(pattern, str):
        try:
            return int(Target[pattern.upper()])
        except KeyError:
            names = ", ".join(repr(t.name.lower()) for t in Target)
            raise ValueError(f"{function}() argument 'pattern' = {pattern!r} is not "
                             f"one of {names}") from None
    return int(as_index(function, "pattern", pattern))


class Calibration:
    """The calibration model of a dual-line-laser sensor.

    ``Calibration()`` is empty and unfinished: fill it through the setters
    and the estimate_* methods (intrinsics first: a homography is estimated
    through them), then :meth:`finish` checks that every part is present and
    freezes it. ``Calibration.load(path)`` / ``loads(text)`` give a finished
    model; ``Calibration.reference()`` is the reference sensor.

    Mapping (:meth:`image_to_plane`, :meth:`plane_to_image`) and saving need
    a finished model; a setter on a finished model raises StateError.

    Frames: image points (u, v) in px, u right, v down, origin at the centre
    of the top-left pixel; "raw" points are what the camera sees (distorted).
    Laser planes: (x, z) in mm, x across the width, z up. Laser L (0 or 1) at
    encoder reading e sees material s = e - offset_L.

    Threads: a finished model is immutable and may be used from any number
    of threads at once (the mapping calls release the GIL and run in
    parallel); calls on an unfinished one are serialised by a lock.
    Use it as a context manager, or call :meth:`close`, to free it
    deterministically. Finished models pickle (as their saved text).
    """

    def __init__(self) -> None:
        self._lock = threading.RLock()
        self._handle: Optional[_capi.flt_calib] = _capi.flt_calib_create()
        self._finished = False

    @classmethod
    def _wrap(cls, handle: _capi.flt_calib) -> "Calibration":
        self = cls.__new__(cls)
        self._lock = threading.RLock()
        self._handle = handle
        self._finished = bool(_capi.flt_calib_is_finished(handle))
        return self

    # -- construction from files and factories -----------------------------

    @classmethod
    def load(cls, path: PathLike) -> "Calibration":
        """Reads a model saved by :meth:`save`; it is finished.

        Raises FileError (an OSError) if the file cannot be read, FormatError
        (a ValueError) if it is malformed, with a message naming the field
        (e.g. "lasers[1].homography[4]")."""
        return cls._wrap(_capi.flt_calib_load(_path("load", path)))

    @classmethod
    def loads(cls, text: Union[str, bytes]) -> "Calibration":
        """The same as :meth:`load` from the text of a file (str, or UTF-8
        bytes)."""
        if isinstance(text, (bytes, bytearray, memoryview)):
            try:
                text = bytes(text).decode("utf-8")
            except UnicodeDecodeError as exc:
                raise ValueError(f"loads() argument 'text' is not UTF-8: {exc}") from None
        elif not isinstance(text, str):
            raise TypeError(f"loads() argument 'text' must be str or bytes, not "
                            f"{type(text).__name__}")
        return cls._wrap(_capi.flt_calib_load_text(text))

    @classmethod
    def reference(cls, first_row: int = 0, rows: int = 2048, first_x_mm: float = -1000.0,
                  pitch_mm: float = 2.0, fibers: int = 1001) -> "Calibration":
        """The reference sensor as a finished model: a 2048 x 2048 camera,
        f = 6 mm lens (fx = fy = 1090.9 px), mounted 1140 mm above the strip
        looking down at 45 degrees, laser offsets -50 and +50 mm (laser
        spacing 100 mm), encoder 0.01 mm per count. At z = 0 the lines lie
        near rows 996 (laser 1) and 1044 (laser 0); +1 mm moves them about
        0.48 px up.

        Args:
            first_row, rows: the rows read out (an ROI, px); first_row + rows
                <= 2048. The principal point moves with the ROI.
            first_x_mm, pitch_mm, fibers: the fiber grid, mm.
        """
        fn = "reference"
        return cls._wrap(_capi.flt_calib_create_reference(
            as_index(fn, "first_row", first_row, 0, 2**32 - 1),
            as_index(fn, "rows", rows, 0, 2**32 - 1),
            as_real(fn, "first_x_mm", first_x_mm), as_real(fn, "pitch_mm", pitch_mm),
            as_index(fn, "fibers", fibers)))

    # -- lifetime -------------------------------------------------------------

    def close(self) -> None:
        """Frees the C model now. Idempotent; any later call raises
        StateError. Objects built from it (SimulatedLine) keep their own
        copy."""
        with self._lock:
            self._handle = None

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._handle is None

    def __enter__(self) -> "Calibration":
        self._live()
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def _live(self) -> _capi.flt_calib:
        handle = self._handle
        if handle is None:
            raise StateError("the Calibration is closed")
        return handle

    def _reading(self):
        # A finished model is immutable: readers need no lock (and map in
        # parallel). An unfinished one may be changed by another thread.
        return contextlib.nullcontext() if self._finished else self._lock

    def __reduce__(self):
        if not self._finished:
            raise TypeError("only a finished Calibration can be pickled")
        return (Calibration.loads, (self.dumps(),))

    def __repr__(self) -> str:
        if getattr(self, "_handle", None) is None:  # closed, or __init__ failed
            return "<flatline.Calibration closed>"
        state = "finished" if self._finished else "unfinished"
        try:
            width, height = self.frame_size
            frame = f" frame={width}x{height}"
        except StateError:
            frame = ""
        return f"<flatline.Calibration {state}{frame}>"

    # -- finishing ------------------------------------------------------------

    def finish(self) -> None:
        """Checks that intrinsics, frame size, both homographies, both laser
        offsets (distinct), the encoder scale and the fiber grid are set,
        then freezes the model. StateError names the first missing part (the
        model stays unfinished and usable); finishing twice is a StateError
        too."""
        with self._lock:
            _capi.flt_calib_finish(self._live())
            self._finished = True

    @property
    def finished(self) -> bool:
        """True once finished (loaded models are)."""
        with self._reading():
            return bool(_capi.flt_calib_is_finished(self._live()))

    # -- saving -----------------------------------------------------------------

    def save(self, path: PathLike) -> None:
        """Writes the finished model to `path` as JSON (through a temporary
        file renamed into place). Every double is written with 17 digits, so
        save -> load -> save is byte-identical. FileError if it cannot be
        written; StateError if the model is not finished."""
        path = _path("save", path)
        with self._reading():
            _capi.flt_calib_save(self._live(), path)

    def dumps(self) -> str:
        """The text :meth:`save` writes, as a str."""
        with self._reading():
            return self._live().save_text_bytes().decode("utf-8")

    # -- camera -----------------------------------------------------------------

    @property
    def frame_size(self) -> Tuple[int, int]:
        """(width, height) of the frames, px (each 1 .. 65536). Set it before
        estimating intrinsics. StateError while unset."""
        with self._reading():
            width, height = _capi.flt_calib_get_frame_size(self._live())
        return int(width), int(height)

    @frame_size.setter
    def frame_size(self, size: Tuple[int, int]) -> None:
        fn = "frame_size"
        width, height = _pair(fn, size)
        width = as_index(fn, "width", width, 0, 2**32 - 1)
        height = as_index(fn, "height", height, 0, 2**32 - 1)
        with self._lock:
            _capi.flt_calib_set_frame_size(self._live(), width, height)

    @property
    def intrinsics(self) -> Intrinsics:
        """The camera intrinsics and distortion (:class:`Intrinsics`).
        Assign an Intrinsics or a dict with fx, fy, cx, cy (px) and any of
        k1..k6, p1, p2 (0 when absent). StateError while unset."""
        camera = np.empty(4)
        distortion = np.empty(8)
        with self._reading():
            self._live().get_intrinsics_into(camera, distortion)
        return Intrinsics.from_arrays(camera, distortion)

    @intrinsics.setter
    def intrinsics(self, value: Union[Intrinsics, Mapping[str, float]]) -> None:
        self.set_intrinsics(value)

    def set_intrinsics(self, intrinsics: Union[Intrinsics, Mapping[str, float], None] = None,
                       **values: float) -> None:
        """Sets the intrinsics: an :class:`Intrinsics`, a dict, or keywords
        fx, fy, cx, cy (px, fx and fy > 0) and k1..k6, p1, p2 (default 0).
        Non-finite values and fx, fy <= 0 raise InvalidArgumentError naming
        the value."""
        fn = "set_intrinsics"
        if intrinsics is not None and values:
            raise TypeError(f"{fn}() takes an Intrinsics or keywords, not both")
        if isinstance(intrinsics, Intrinsics):
            value = intrinsics
        else:
            fields = dict(values) if intrinsics is None else intrinsics
            if not isinstance(fields, Mapping):
                raise TypeError(f"{fn}() argument must be an Intrinsics or a mapping, "
                                f"not {type(fields).__name__}")
            known = {f.name for f in dataclasses.fields(Intrinsics)}
            for key in fields:
                if key not in known:
                    raise TypeError(f"{fn}() got an unexpected key '{key}' (intrinsics "
                                    f"are {', '.join(sorted(known))})")
            for key in ("fx", "fy", "cx", "cy"):
                if key not in fields:
                    raise TypeError(f"{fn}() is missing '{key}'")
            value = Intrinsics(**{k: as_real(fn, k, v) for k, v in fields.items()})
        camera = np.array([as_real(fn, k, getattr(value, k)) for k in ("fx", "fy", "cx", "cy")])
        distortion = np.array([as_real(fn, k, getattr(value, k)) for k in _DISTORTION_NAMES])
        with self._lock:
            self._live().set_intrinsics_array(camera, distortion)

    def estimate_intrinsics(self, images: Any, *, pattern: Union[str, Target] = "chessboard",
                            columns: int, rows: int, pitch_mm: float,
                            rational_distortion: bool = False) -> IntrinsicsFit:
        """Estimates the intrinsics from images of a planar target (OpenCV's
        detection, sub-pixel corner refinement and calibrateCamera) and
        stores them in the model.

        Args:
            images: a sequence of 2-D uint8 grey images (height, width) of the
                frame size, or one (views, height, width) uint8 array (passed
                without a copy when C-contiguous). Not retained.
            pattern: "chessboard" (columns x rows *inner* corners),
                "circle_grid" or "asymmetric_circle_grid", or a Target.
            columns, rows: the target layout (>= 3).
            pitch_mm: square side or circle spacing, mm.
            rational_distortion: also estimate k4..k6.

        Returns:
            IntrinsicsFit(rms_px, view_rms_px, intrinsics). Views without a
            detected target are skipped (NaN in view_rms_px).

        Raises NumericError (an ArithmeticError) with fewer than 3 usable
        views, leaving the model unchanged; StateError without a frame size
        or on a finished model. The GIL is released while OpenCV works.
        """
        fn = "estimate_intrinsics"
        target = _target(fn, pattern)
        columns = as_index(fn, "columns", columns, 0, 2**32 - 1)
        rows = as_index(fn, "rows", rows, 0, 2**32 - 1)
        pitch_mm = as_real(fn, "pitch_mm", pitch_mm)
        if not isinstance(rational_distortion, (bool, np.bool_)):
            raise TypeError(f"{fn}() argument 'rational_distortion' must be a bool")
        try:
            width, height = self.frame_size
        except StateError as exc:
            raise StateError(f"{fn}() needs the frame size: set Calibration.frame_size "
                             f"first ({exc.message})", exc.status) from None
        stack = _image_stack(fn, images, (height, width))
        bag = make_options(fn, {"calib_rational_distortion": float(bool(rational_distortion))})
        view_rms = np.empty(stack.shape[0])
        with self._lock:
            rms = self._live().estimate_intrinsics_stack(
                stack, target, columns, rows, pitch_mm, bag, view_rms)
        return IntrinsicsFit(float(rms), view_rms, self.intrinsics)

    def undistort(self, points: Any) -> np.ndarray:
        """Raw (distorted) image points (N, 2) px -> undistorted (ideal
        pinhole) points (N, 2) px in the same frame, to about 1e-9 px; NaN
        where the inverse does not converge. Needs only the intrinsics.
        The GIL is released."""
        fn = "undistort"
        pts = as_points(fn, "points", points)
        out = np.empty(pts.shape)
        with self._reading():
            self._live().undistort_into(pts, out)
        return out

    # -- laser planes ---------------------------------------------------------

    def homography(self, laser: int) -> np.ndarray:
        """Laser `laser`'s homography (3, 3): undistorted (u, v, 1) px ->
        (x, z, 1) mm on its plane. StateError while unset."""
        h = np.empty((3, 3))
        laser = _laser("homography", laser)
        with self._reading():
            self._live().get_homography_into(laser, h)
        return h

    def set_homography(self, laser: int, h: Any) -> None:
        """Sets laser `laser`'s homography directly, (3, 3); it must be finite
        and invertible (InvalidArgumentError otherwise)."""
        fn = "set_homography"
        laser = _laser(fn, laser)
        matrix = as_float64(fn, "h", h, 2)
        if matrix.shape != (3, 3):
            raise ValueError(f"{fn}() argument 'h' must have shape (3, 3), got {matrix.shape}")
        with self._lock:
            self._live().set_homography_array(laser, matrix)

    def estimate_homography(self, laser: int, image_points: Any, plane_points: Any, *,
                            ransac: bool = False, **options: OptionValue) -> HomographyFit:
        """Estimates laser `laser`'s homography from correspondences and
        stores it (the intrinsics must be set: the image points are
        undistorted through them first). Normalised DLT, then
        Levenberg-Marquardt on the image reprojection error, optionally
        inside RANSAC; deterministic.

        Args:
            laser: 0 or 1.
            image_points: (N, 2) raw image points (u, v), px.
            plane_points: (N, 2) the same points on the laser plane (x, z), mm.
            ransac: reject outliers with RANSAC.
            **options: calib_ransac_threshold (px, default 1),
                calib_ransac_iterations (default 1000), calib_ransac_seed
                (default 1).

        Returns:
            HomographyFit(rms_px, rms_mm, residual_px, residual_mm, inliers,
            homography); residuals are (N,), inliers (N,) bool (all True
            without RANSAC); the RMS values are over the inliers.

        Raises NumericError for a degenerate set (fewer than 4 points, or
        collinear), leaving the model unchanged. The GIL is released.
        """
        fn = "estimate_homography"
        laser = _laser(fn, laser)
        image = as_points(fn, "image_points", image_points)
        plane = as_points(fn, "plane_points", plane_points)
        if plane.shape != image.shape:
            raise ValueError(f"{fn}() argument 'plane_points' has shape {plane.shape}, "
                             f"but image_points requires {image.shape}")
        if not isinstance(ransac, (bool, np.bool_)):
            raise TypeError(f"{fn}() argument 'ransac' must be a bool")
        settings = dict(options)
        if "calib_ransac" in settings:
            raise TypeError(f"{fn}() takes RANSAC as 'ransac=True', not 'calib_ransac'")
        settings["calib_ransac"] = 1.0 if ransac else 0.0
        bag = make_options(fn, settings, prefixes=("calib_ransac",))
        count = image.shape[0]
        residual_px = np.empty(count)
        residual_mm = np.empty(count)
        inliers = np.empty(count, dtype=np.uint8)
        with self._lock:
            rms_px, rms_mm = self._live().estimate_homography_arrays(
                laser, image, plane, bag, residual_px, residual_mm, inliers)
        return HomographyFit(float(rms_px), float(rms_mm), residual_px, residual_mm,
                             inliers.view(np.bool_), self.homography(laser))

    # -- sensor geometry --------------------------------------------------------

    def laser_offset(self, laser: int) -> float:
        """Laser `laser`'s offset along travel, mm. StateError while unset."""
        laser = _laser("laser_offset", laser)
        with self._reading():
            return float(_capi.flt_calib_get_laser_offset(self._live(), laser))

    def set_laser_offset(self, laser: int, offset_mm: float) -> None:
        """Sets laser `laser`'s offset along travel, mm (finite)."""
        fn = "set_laser_offset"
        laser = _laser(fn, laser)
        offset_mm = as_real(fn, "offset_mm", offset_mm)
        with self._lock:
            _capi.flt_calib_set_laser_offset(self._live(), laser, offset_mm)

    @property
    def laser_offsets(self) -> Tuple[float, float]:
        """(offset_0, offset_1), mm along travel; laser L at encoder e reads
        material s = e - offset_L. Assign a pair to set both."""
        return self.laser_offset(0), self.laser_offset(1)

    @laser_offsets.setter
    def laser_offsets(self, offsets: Tuple[float, float]) -> None:
        fn = "laser_offsets"
        pair = [as_real(fn, f"laser_offsets[{i}]", v) for i, v in enumerate(_pair(fn, offsets))]
        for i, value in enumerate(pair):  # both or neither
            if not math.isfinite(value):
                raise ValueError(f"{fn}: 'laser_offsets[{i}]' = {value} is not finite")
        with self._lock:
            for laser, value in enumerate(pair):
                self.set_laser_offset(laser, value)

    @property
    def laser_spacing(self) -> float:
        """Delta-d = offset_1 - offset_0, mm (positive when laser 1 is further
        along travel). StateError unless both offsets are set."""
        with self._reading():
            return float(_capi.flt_calib_laser_spacing(self._live()))

    @property
    def encoder_scale(self) -> float:
        """Encoder scale, mm of travel per count (finite, non-zero; negative
        when the encoder counts down as the strip moves forward)."""
        with self._reading():
            return float(_capi.flt_calib_get_encoder_scale(self._live()))

    @encoder_scale.setter
    def encoder_scale(self, mm_per_count: float) -> None:
        value = as_real("encoder_scale", "mm_per_count", mm_per_count)
        with self._lock:
            _capi.flt_calib_set_encoder_scale(self._live(), value)

    @property
    def fiber_grid(self) -> FiberGrid:
        """FiberGrid(first_x_mm, pitch_mm, count): fiber k at x = first_x_mm
        + k * pitch_mm. Assign a triple to set it (pitch > 0, count >= 1)."""
        with self._reading():
            first_x, pitch, count = _capi.flt_calib_get_fiber_grid(self._live())
        return FiberGrid(float(first_x), float(pitch), int(count))

    @fiber_grid.setter
    def fiber_grid(self, grid: Tuple[float, float, int]) -> None:
        fn = "fiber_grid"
        try:
            first_x, pitch, count = grid
        except (TypeError, ValueError):
            raise TypeError(f"{fn} must be set to (first_x_mm, pitch_mm, count)") from None
        first_x = as_real(fn, "first_x_mm", first_x)
        pitch = as_real(fn, "pitch_mm", pitch)
        count = as_index(fn, "count", count)
        with self._lock:
            _capi.flt_calib_set_fiber_grid(self._live(), first_x, pitch, count)

    @property
    def fiber_x(self) -> np.ndarray:
        """The (K,) fiber positions across the width, mm."""
        return self.fiber_grid.x

    # -- mapping (finished model) -------------------------------------------------

    def image_to_plane(self, laser: int, points: Any) -> np.ndarray:
        """Raw image points (N, 2) (u, v) px -> laser `laser`'s plane (N, 2)
        (x, z) mm. A NaN point maps to NaN (an invalid peak stays invalid).
        Finished model only; thread-safe; the GIL is released."""
        fn = "image_to_plane"
        laser = _laser(fn, laser)
        pts = as_points(fn, "points", points)
        out = np.empty(pts.shape)
        with self._reading():
            self._live().image_to_plane_into(laser, pts, out)
        return out

    def plane_to_image(self, laser: int, points: Any) -> np.ndarray:
        """Laser `laser`'s plane points (N, 2) (x, z) mm -> raw image points
        (N, 2) (u, v) px; NaN behind the camera or at infinity. Finished
        model only; thread-safe; the GIL is released."""
        fn = "plane_to_image"
        laser = _laser(fn, laser)
        pts = as_points(fn, "points", points)
        out = np.empty(pts.shape)
        with self._reading():
            self._live().plane_to_image_into(laser, pts, out)
        return out


def _pair(function: str, value: Any) -> Tuple[Any, Any]:
    try:
        first, second = value
    except (TypeError, ValueError):
        raise TypeError(f"{function} must be set to a pair, not {value!r}") from None
    return first, second


def _image_stack(function: str, images: Any, frame: Tuple[int, int]) -> np.ndarray:
    """The target images as one C-contiguous (views, height, width) uint8
    block; a 3-D uint8 C-contiguous array passes through without a copy."""
    height, width = frame
    if isinstance(images, np.ndarray):
        if images.ndim != 3:
            raise TypeError(f"{function}() argument 'images' must be a sequence of 2-D "
                            f"uint8 arrays or one (views, height, width) array, not an "
                            f"array of shape {images.shape}")
        views = [images[i] for i in range(images.shape[0])]
        whole = images
    elif isinstance(images, (str, bytes)) or not isinstance(images, Sequence):
        raise TypeError(f"{function}() argument 'images' must be a sequence of 2-D "
                        f"uint8 arrays, not {type(images).__name__}")
    else:
        views = list(images)
        whole = None
    for i, view in enumerate(views):
        view = np.asanyarray(view)
        if view.dtype != np.uint8:
            raise TypeError(f"{function}() argument 'images[{i}]' has dtype {view.dtype}; "
                            f"8-bit grey images (uint8) are needed")
        if view.shape != (height, width):
            raise ValueError(f"{function}() argument 'images[{i}]' has shape {view.shape}, "
                             f"but the frame size requires {(height, width)}")
    if whole is not None:
        return np.require(whole, requirements=("C", "A"))
    if not views:
        return np.empty((0, height, width), dtype=np.uint8)
    return np.stack([np.asarray(v) for v in views])
