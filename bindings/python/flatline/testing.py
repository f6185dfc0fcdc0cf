# SPDX-License-Identifier: Apache-2.0
"""The testing tier (flatline/testing.h, libflatline_testing): simulated USB3
Vision cameras on a simulated USB bus, with fault injection, so acquisition
and its failure modes run without hardware::

    from flatline.testing import U3VSimBus
    with U3VSimBus() as bus:
        bus.add_camera("Vendor", "Model", "SN1", 2048, 256)
        with flatline.Source.u3v("SN1", bus=bus) as camera:
            ...

Not under libflatline's ABI promise: names and behaviour here may change in
any release. This module loads its own extension (flatline._testing_capi and
libflatline_testing beside it); ``import flatline`` never does.
"""

from __future__ import annotations

import enum
import threading
from typing import Any, Dict, List, Optional, Union

from . import testing_capi as _tcapi
from ._arrays import as_index
from ._errors import StateError
from ._extractor import _format as _pixel_format_arg
from ._pixels import PixelFormat
from ._sim import SimulatedLine
from ._source import CameraInfo, _enum, _str, list_cameras

__all__ = ["U3VFault", "U3VSimParam", "U3VSimBus"]


class U3VFault(enum.IntEnum):
    """Faults of the simulated camera (:meth:`U3VSimBus.inject`). Stream
    faults hit the frame with block id ``at``; host faults (SUBMIT_REFUSED
    and the control-channel faults) hit ``count`` operations (bulk
    submissions, GenCP commands) after the next ``at`` ones."""

    SHORT_FRAME = _tcapi.FLT_U3V_FAULT_SHORT_FRAME
    LEADER_MID_FRAME = _tcapi.FLT_U3V_FAULT_LEADER_MID_FRAME
    OVERFLOW = _tcapi.FLT_U3V_FAULT_OVERFLOW
    SKIP_BLOCK_IDS = _tcapi.FLT_U3V_FAULT_SKIP_BLOCK_IDS
    STREAM_TIMEOUT = _tcapi.FLT_U3V_FAULT_STREAM_TIMEOUT
    UNPLUG = _tcapi.FLT_U3V_FAULT_UNPLUG
    GARBAGE = _tcapi.FLT_U3V_FAULT_GARBAGE
    TRAILER_STATUS = _tcapi.FLT_U3V_FAULT_TRAILER_STATUS
    SUBMIT_REFUSED = _tcapi.FLT_U3V_FAULT_SUBMIT_REFUSED
    PENDING_ACK = _tcapi.FLT_U3V_FAULT_PENDING_ACK
    CONTROL_TIMEOUT = _tcapi.FLT_U3V_FAULT_CONTROL_TIMEOUT
    LATE_ACK = _tcapi.FLT_U3V_FAULT_LATE_ACK
    LOST_ACK = _tcapi.FLT_U3V_FAULT_LOST_ACK
    BUSY = _tcapi.FLT_U3V_FAULT_BUSY
    CONTROL_UNPLUG = _tcapi.FLT_U3V_FAULT_CONTROL_UNPLUG


class U3VSimParam(enum.IntEnum):
    """Parameters of a simulated camera (:meth:`U3VSimBus.set` before a
    camera is opened; the last nine are read-only, :meth:`U3VSimBus.get`)."""

    RESPONSE_TIME_MS = _tcapi.FLT_U3V_SIM_RESPONSE_TIME_MS
    MAX_COMMAND_BYTES = _tcapi.FLT_U3V_SIM_MAX_COMMAND_BYTES
    MAX_ACK_BYTES = _tcapi.FLT_U3V_SIM_MAX_ACK_BYTES
    ALIGNMENT_LOG2 = _tcapi.FLT_U3V_SIM_ALIGNMENT_LOG2
    XML_ZIPPED = _tcapi.FLT_U3V_SIM_XML_ZIPPED
    ENCODER_CHUNK = _tcapi.FLT_U3V_SIM_ENCODER_CHUNK
    ENCODER_CHUNK_ID = _tcapi.FLT_U3V_SIM_ENCODER_CHUNK_ID
    ENCODER_MM_PER_COUNT_UM = _tcapi.FLT_U3V_SIM_ENCODER_MM_PER_COUNT_UM
    SPEED_MBPS = _tcapi.FLT_U3V_SIM_SPEED_MBPS
    LEFT_STREAMING = _tcapi.FLT_U3V_SIM_LEFT_STREAMING
    SI_CONTROL = _tcapi.FLT_U3V_SIM_SI_CONTROL
    ACQUIRING = _tcapi.FLT_U3V_SIM_ACQUIRING
    COMMANDS = _tcapi.FLT_U3V_SIM_COMMANDS
    LAST_READ_TIMEOUT_MS = _tcapi.FLT_U3V_SIM_LAST_READ_TIMEOUT_MS
    FRAMES_SENT = _tcapi.FLT_U3V_SIM_FRAMES_SENT
    OPEN = _tcapi.FLT_U3V_SIM_OPEN
    FAULTS_PENDING = _tcapi.FLT_U3V_SIM_FAULTS_PENDING
    UNPLUGGED = _tcapi.FLT_U3V_SIM_UNPLUGGED


class U3VSimBus:
    """A simulated USB bus with simulated USB3 Vision cameras (at most 8, plus
    one device that is not a camera): the real client code runs against it,
    down to the USB transfers, so acquisition and its failure modes can be
    tested without hardware. Time is virtual: simulated timeouts return at
    once.

    Frames are a test pattern (byte i of block b is (b*131 + i*7 + (i>>9))
    mod 256) unless :meth:`set_frames` gives a camera a
    :class:`~flatline.SimulatedLine` to render. Feature registers: see
    flatline/testing.h.

    Sources opened on the bus (:meth:`flatline.Source.u3v` with ``bus=``)
    keep the C bus alive: :meth:`close` frees it once they are closed too.
    Not for use from two threads at once (the binding serialises calls on it
    and on its sources).
    """

    def __init__(self) -> None:
        self._lock = threading.RLock()
        self._handle: Optional[_tcapi.flt_u3v_sim] = _tcapi.flt_u3v_sim_create()
        # camera index -> the SimulatedLine it renders (kept alive: the C bus
        # borrows it).
        self._frames: Dict[int, SimulatedLine] = {}
        self._sim_handles: Dict[int, Any] = {}

    def close(self) -> None:
        """Releases the bus (freed once no source opened on it is left).
        Idempotent; later calls raise StateError."""
        with self._lock:
            self._handle = None

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._handle is None

    def __enter__(self) -> "U3VSimBus":
        self._live()
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def _live(self) -> _tcapi.flt_u3v_sim:
        handle = self._handle
        if handle is None:
            raise StateError("the U3VSimBus is closed")
        return handle

    def _transport(self) -> Any:
        """The bus as the flt_usb_transport flatline.Source.u3v and
        flatline.list_cameras pass to libflatline (owned by the C bus)."""
        return _tcapi.flt_u3v_sim_transport(self._live())

    def __repr__(self) -> str:
        if getattr(self, "_handle", None) is None:
            return "<flatline.testing.U3VSimBus closed>"
        return "<flatline.testing.U3VSimBus>"

    def add_camera(self, vendor: str, model: str, serial: str, width: int, height: int,
                   pixel_format: Union[PixelFormat, str, int] = PixelFormat.MONO8) -> int:
        """Adds a camera with a width x height sensor (16..8192 px each) of
        Mono8/10/12/16 pixels; strings at most 63 bytes. Returns its index."""
        fn = "add_camera"
        fmt = _pixel_format_arg(fn, pixel_format)
        args = (_str(fn, "vendor", vendor), _str(fn, "model", model),
                _str(fn, "serial", serial), as_index(fn, "width", width, 0, 2**32 - 1),
                as_index(fn, "height", height, 0, 2**32 - 1))
        with self._lock:
            return int(_tcapi.flt_u3v_sim_add_camera(self._live(), *args, int(fmt)))

    def set_frames(self, camera: int, sim: Optional[SimulatedLine]) -> None:
        """Camera `camera` renders `sim`'s frames (the bus keeps it; the
        camera takes its frame size and format), or the test pattern with
        None."""
        fn = "set_frames"
        camera = as_index(fn, "camera", camera)
        if sim is not None and not isinstance(sim, SimulatedLine):
            raise TypeError(f"{fn}() argument 'sim' must be a SimulatedLine or None, not "
                            f"{type(sim).__name__}")
        with self._lock:
            sim_handle = sim._live() if sim is not None else None
            _tcapi.flt_u3v_sim_set_frames(self._live(), camera, sim_handle)
            if sim is None:
                self._frames.pop(camera, None)
                self._sim_handles.pop(camera, None)
            else:
                self._frames[camera] = sim
                self._sim_handles[camera] = sim_handle

    def set(self, camera: int, param: Union[U3VSimParam, str, int], value: int) -> None:
        """Sets a parameter of camera `camera` (before it is opened)."""
        fn = "set"
        camera = as_index(fn, "camera", camera)
        key = _enum(fn, "param", param, U3VSimParam)
        value = as_index(fn, "value", value, 0, 2**64 - 1)
        with self._lock:
            _tcapi.flt_u3v_sim_set(self._live(), camera, key, value)

    def get(self, camera: int, param: Union[U3VSimParam, str, int]) -> int:
        """A parameter or read-only state of camera `camera`."""
        fn = "get"
        camera = as_index(fn, "camera", camera)
        key = _enum(fn, "param", param, U3VSimParam)
        with self._lock:
            return int(_tcapi.flt_u3v_sim_get(self._live(), camera, key))

    def inject(self, camera: int, fault: Union[U3VFault, str, int], at: int = 0,
               count: int = 1) -> None:
        """Schedules a fault (see :class:`U3VFault`): stream faults on the
        frame with block id `at`, host faults on `count` operations after the
        next `at` ones (0: from the next one on). Faults add up."""
        fn = "inject"
        camera = as_index(fn, "camera", camera)
        key = _enum(fn, "fault", fault, U3VFault)
        at = as_index(fn, "at", at, 0, 2**64 - 1)
        count = as_index(fn, "count", count, 0, 2**32 - 1)
        with self._lock:
            _tcapi.flt_u3v_sim_inject(self._live(), camera, key, at, count)

    def peek(self, camera: int, address: int) -> int:
        """A 32-bit register of the camera's map, read directly (no GenCP)."""
        fn = "peek"
        camera = as_index(fn, "camera", camera)
        address = as_index(fn, "address", address, 0, 2**64 - 1)
        with self._lock:
            return int(_tcapi.flt_u3v_sim_peek(self._live(), camera, address))

    def cameras(self) -> List[CameraInfo]:
        """The cameras on this bus, as :func:`list_cameras` finds them."""
        return list_cameras(self)
