# SPDX-License-Identifier: Apache-2.0
"""libflatline for Python: online flatness of steel strip from a
dual-line-laser + camera sensor.

Arrays are numpy float64, rows along travel x fibers across the width;
lengths in mm, slopes in mm/mm. Errors raise subclasses of FlatlineError.

    >>> import flatline
    >>> z = flatline.reconstruct(s, height, slope, laser_spacing=100.0)

    >>> calib = flatline.Calibration.load("sensor.json")
    >>> with flatline.SimulatedLine(calib, sim_seed=7) as sim:
    ...     sim.add_defect("centre_buckle", 12.0, 1800.0)
    ...     rows = sim.next_rows(3000)

Components: the calibration model (Calibration), the simulated sensor
(SimulatedLine), frame sources (Source: simulator, image sequences, USB3
Vision cameras), the frame-to-profile extractor (Extractor), the
reconstructor (reconstruct, Reconstructor), the flatness metrics (Flatness,
i_units), and the gauge that runs them all on a line (Gauge: frames and
cuts in, Sheet results out). Simulated USB3 Vision cameras for tests are
in flatline.testing (the testing tier, loaded only when imported).
"""

from __future__ import annotations

from . import capi as _capi
from ._errors import (
    BufferFullError,
    DeviceError,
    FileError,
    FlatlineError,
    FormatError,
    InternalError,
    InvalidArgumentError,
    NotFoundError,
    NumericError,
    OutOfMemoryError,
    StateError,
    TimeoutError,
)
from ._calib import (
    LASERS,
    Calibration,
    FiberGrid,
    HomographyFit,
    Intrinsics,
    IntrinsicsFit,
    Target,
)
from ._options import OptionInfo, option_info, options
from ._recon import (
    FLAG_GAP,
    FLAG_INVALID_INPUT,
    FLAG_NO_DATA,
    Reconstructor,
    reconstruct,
    reconstruct_with_flags,
    reconstructor_options,
    release_reconstruct_memory,
)
from ._extractor import ExtractedRow, Extractor, extractor_options
from ._pixels import PixelFormat
from ._sim import (
    Defect,
    SimFrame,
    SimRows,
    SimulatedLine,
    simulator_options,
)
from ._flatness import (
    FIBER_NO_DATA,
    FIBER_NO_WAVE,
    FIBER_PARTIAL,
    WINDOW_NO_BOW,
    WINDOW_NO_CROSSBOW,
    WINDOW_NO_VALID_FIBER,
    WINDOW_SHORT,
    ZONE_NO_DATA,
    FiberResults,
    Flatness,
    FlatnessResult,
    Shape,
    ShapeComponent,
    ShapeResult,
    WindowInfo,
    ZoneResults,
    flatness_options,
    i_units,
)
from ._source import (
    CameraInfo,
    Frame,
    Source,
    SourceKind,
    list_cameras,
    source_options,
)

# The line in the field (strip edges, off-strip flags, saturation, zones on
# the strip).
from ._recon import FLAG_OFF_STRIP, reconstruct_flagged
from ._extractor import (
    STRIP_LEFT_OPEN,
    STRIP_NONE,
    STRIP_RIGHT_OPEN,
    STRIP_LEFT_GLINT,
    STRIP_RIGHT_GLINT,
    Saturation,
    StripEdges,
)
from ._flatness import FIBER_OFF_STRIP, WINDOW_ON_STRIP, ZONE_OFF_STRIP, StripWindow

from . import _log
from ._gauge import (CoilStats, Gauge, RuleStats, Sheet, SheetFlag, SheetNote, SheetZones,
                     gauge_options)
from ._advisor import Actuator, Advice, Advisor, AdvisorFit, advisor_options
from ._record import (
    Archive,
    CoilInfo,
    RecordedRows,
    Recorder,
    Recording,
    archive_options,
    record_options,
)
from ._verdict import (
    Measure,
    RuleResult,
    ToleranceRule,
    ToleranceRules,
    Verdict,
    VerdictState,
    straightedge_deviation,
)

#: The version of the C headers this binding was built against.
__version__: str = _capi.FLT_HEADER_VERSION


def version() -> str:
    """The version of the loaded C library, "MAJOR.MINOR.PATCH"."""
    return _capi.flt_version_string()


# SQLite's check: the loaded library must be the one the binding was built
# for (same ABI, and not older than the headers). The ABI is the major
# version, and while that is 0 the minor version too (the SONAME rule).
def _abi(number: int) -> "tuple[int, int]":
    major, minor = number // 10000, number // 100 % 100
    return (major, minor if major == 0 else 0)


if (_abi(_capi.flt_version()) != _abi(_capi.FLT_HEADER_VERSION_NUMBER)
        or _capi.flt_version() < _capi.FLT_HEADER_VERSION_NUMBER):
    raise ImportError(
        f"flatline {__version__} was built for libflatline "
        f"{__version__} but loaded libflatline {version()}"
    )

__all__ = [
    "__version__",
    "CoilInfo",
    "SheetNote",
    "Recorder",
    "Recording",
    "RecordedRows",
    "Archive",
    "record_options",
    "archive_options",
    "version",
    "FlatlineError",
    "InvalidArgumentError",
    "OutOfMemoryError",
    "StateError",
    "BufferFullError",
    "FileError",
    "FormatError",
    "DeviceError",
    "TimeoutError",
    "NotFoundError",
    "NumericError",
    "InternalError",
    "OptionInfo",
    "option_info",
    "options",
    "FLAG_INVALID_INPUT",
    "FLAG_GAP",
    "FLAG_NO_DATA",
    "Reconstructor",
    "reconstruct",
    "reconstruct_with_flags",
    "reconstructor_options",
    "release_reconstruct_memory",
    "LASERS",
    "Target",
    "Intrinsics",
    "FiberGrid",
    "IntrinsicsFit",
    "HomographyFit",
    "Calibration",
    "Defect",
    "PixelFormat",
    "SimRows",
    "SimFrame",
    "SimulatedLine",
    "simulator_options",
    "ExtractedRow",
    "Extractor",
    "extractor_options",
    "FIBER_NO_DATA",
    "FIBER_NO_WAVE",
    "FIBER_PARTIAL",
    "ZONE_NO_DATA",
    "WINDOW_SHORT",
    "WINDOW_NO_VALID_FIBER",
    "WINDOW_NO_BOW",
    "WINDOW_NO_CROSSBOW",
    "Shape",
    "ShapeComponent",
    "FiberResults",
    "ZoneResults",
    "ShapeResult",
    "WindowInfo",
    "FlatnessResult",
    "Flatness",
    "flatness_options",
    "i_units",
    "SourceKind",
    "Frame",
    "CameraInfo",
    "Source",
    "list_cameras",
    "source_options",
    "Gauge",
    "Sheet",
    "SheetFlag",
    "SheetZones",
    "CoilStats",
    "RuleStats",
    "gauge_options",
    "Measure",
    "RuleResult",
    "ToleranceRule",
    "ToleranceRules",
    "Verdict",
    "VerdictState",
    "straightedge_deviation",
    "FLAG_OFF_STRIP",
    "reconstruct_flagged",
    "STRIP_LEFT_OPEN",
    "STRIP_NONE",
    "STRIP_RIGHT_OPEN",
    "STRIP_LEFT_GLINT",
    "STRIP_RIGHT_GLINT",
    "Saturation",
    "StripEdges",
    "FIBER_OFF_STRIP",
    "WINDOW_ON_STRIP",
    "ZONE_OFF_STRIP",
    "StripWindow",
    "Actuator",
    "Advice",
    "Advisor",
    "AdvisorFit",
    "advisor_options",
]
