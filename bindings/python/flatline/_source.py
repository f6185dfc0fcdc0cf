# SPDX-License-Identifier: Apache-2.0
"""Frame sources (flatline/source.h): the simulator, recorded image
sequences and USB3 Vision cameras behind one class. (Simulated USB3 Vision
cameras, for testing acquisition without hardware, are in flatline.testing.)"""

from __future__ import annotations

import enum
import os
import threading
from contextlib import ExitStack
from typing import (TYPE_CHECKING, Any, Dict, Iterator, List, NamedTuple, Optional, Sequence,
                    Union)

import numpy as np

from . import _tables
from . import capi as _capi
from ._arrays import as_index, as_real
from ._calib import _path
from ._errors import StateError
from ._options import OptionValue, make_options, options_doc, prefixed_options
from ._pixels import PixelFormat
from ._sim import SimulatedLine

if TYPE_CHECKING:  # the testing tier is imported only when a bus is given
    from .testing import U3VSimBus

__all__ = [
    "SourceKind",
    "Frame",
    "CameraInfo",
    "Source",
    "list_cameras",
    "source_options",
]


class SourceKind(enum.IntEnum):
    """What a :class:`Source` reads from."""

    SIMULATOR = _capi.FLT_SOURCE_SIMULATOR
    IMAGES = _capi.FLT_SOURCE_IMAGES
    U3V = _capi.FLT_SOURCE_U3V
    GIGE = _capi.FLT_SOURCE_GIGE
    RECORDING = _capi.FLT_SOURCE_RECORDING


class Frame(NamedTuple):
    """One frame of a :class:`Source` (a copy: it stays valid after the
    next call)."""

    pixels: np.ndarray  #: (height, width) uint8 (Mono8) or uint16 (Mono10/12/16, data in the low bits)
    pixel_format: PixelFormat  #: the frame's pixel format
    block_id: int  #: the camera's frame counter (simulator and images: the frame index)
    timestamp_ns: int  #: camera: the device clock, ns; else the host's monotonic clock, ns
    encoder_mm: float  #: strip position when the frame was taken, mm (see source_encoder_mode)


class CameraInfo(NamedTuple):
    """A camera found by :func:`list_cameras` (USB3 Vision) or
    :meth:`Source.list_gige_cameras` (GigE Vision)."""

    vendor: str  #: "?" when the camera could not be opened to read its strings
    model: str  #: the model, or why the camera could not be opened
    serial: str  #: the serial number (pass it to :meth:`Source.u3v` / :meth:`Source.gige`)
    speed_mbps: int  #: link speed, Mbit/s (480, 5000, 10000; 0 unknown)
    address: str = ""  #: GigE Vision: "a.b.c.d" (":port" if not 3956); USB3 Vision: ""


#: flt_source_counter by its Python name (counters() keys), in C order.
_COUNTERS = _tables.SOURCE_COUNTERS  # generated from source.h (bindings/gen_tables.py)

_CAMERA_STRINGS = _tables.CAMERA_STRINGS  # generated from source.h (bindings/gen_tables.py)

_CAMERA_VALUES = _tables.CAMERA_VALUES  # generated from source.h (bindings/gen_tables.py)


def source_options() -> Dict[str, float]:
    """The source options (source_*, u3v_*, gige_*) with their C defaults."""
    return {name: info.default
            for name, info in prefixed_options("source_", "u3v_", "gige_").items()}


def _name(function: str, argument: str, value: Any, table: Dict[str, int]) -> int:
    if not isinstance(value, str):
        raise TypeError(f"{function}() argument '{argument}' must be a str, not "
                        f"{type(value).__name__}")
    try:
        return table[value]
    except KeyError:
        raise ValueError(f"{function}() argument '{argument}' = {value!r} is not one of "
                         f"{', '.join(map(repr, table))}") from None


def _str(function: str, argument: str, value: Any) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{function}() argument '{argument}' must be a str, not "
                        f"{type(value).__name__}")
    return value


def _enum(function: str, argument: str, value: Any, cls: type) -> int:
    if isinstance(value, str):
        try:
            return int(cls[value.upper()])
        except KeyError:
            names = ", ".join(repr(m.name.lower()) for m in cls)
            raise ValueError(f"{function}() argument '{argument}' = {value!r} is not one "
                             f"of {names}") from None
    # Any int goes to the library, which names an unknown one.
    return as_index(function, argument, value, -2**31, 2**31 - 1)


def _check_bus(function: str, bus: Any) -> None:
    if bus is None:
        return
    from .testing import U3VSimBus  # the testing tier, only when one is given
    if not isinstance(bus, U3VSimBus):
        raise TypeError(f"{function}() argument 'bus' must be a flatline.testing.U3VSimBus "
                        f"or None, not {type(bus).__name__}")


def list_cameras(bus: Optional["U3VSimBus"] = None) -> List[CameraInfo]:
    """The USB3 Vision cameras present: on the USB bus (libusb) when `bus` is
    None, else on a simulated bus (flatline.testing.U3VSimBus). Cameras that
    cannot be opened (no udev rule) are listed with vendor "?" and the
    reason as their model. DeviceError if libusb cannot start."""
    fn = "list_cameras"
    _check_bus(fn, bus)
    with ExitStack() as stack:
        if bus is not None:
            stack.enter_context(bus._lock)
        handle = _capi.flt_camera_list_create(bus._transport() if bus is not None else None)
        count = int(_capi.flt_camera_list_count(handle))
        found = []
        for index in range(count):
            vendor, model, serial, speed = _capi.flt_camera_list_get(handle, index)
            found.append(CameraInfo(vendor, model, serial, int(speed)))
        return found


class Source:
    """A source of camera frames with their encoder positions: a
    :class:`SimulatedLine`, a recorded image sequence or a USB3 Vision
    camera. Create it with :meth:`simulator`, :meth:`images` or :meth:`u3v`.

        with flatline.Source.simulator(sim) as source:
            source.start()
            frame = source.next()
            row = extractor.process(frame.pixels, frame.encoder_mm)

    Frames are copies: :meth:`next` copies the library's borrowed frame
    (valid only until the next call) into a new numpy array, or into ``out``
    (e.g. the previous frame's pixels: no allocation per frame), so a
    :class:`Frame` stays valid for as long as it is referenced.

    The source keeps what it reads from alive: a Source over a SimulatedLine
    holds it (and its C simulator, even if the SimulatedLine is closed), a
    Source over a :class:`U3VSimBus` holds the bus. Calls are serialised
    (with the simulator's or bus's own calls too); the GIL is released while
    :meth:`next` waits for a camera. Use it as a context manager, or call
    :meth:`close`: that stops a streaming camera cleanly (AcquisitionStop).

    Options:
{options}
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        raise TypeError("create a Source with Source.simulator(), Source.images() or "
                        "Source.u3v()")

    @classmethod
    def _wrap(cls, handle: Any, keep: tuple, locks: tuple,
              bus: Optional["U3VSimBus"] = None) -> "Source":
        self = cls.__new__(cls)
        self._lock = threading.RLock()
        self._handle = handle
        self._keep = keep  # the objects the C source borrows
        self._locks = locks  # their locks, taken around every call
        self._bus = bus  # its simulators render frames in next(): locked too
        self._kind = SourceKind(int(_capi.flt_source_kind_of(handle)))
        return self

    @classmethod
    def open_recording(cls, path: Union[str, "os.PathLike[str]"],
                       **options: OptionValue) -> "Source":
        """A recording (flatline.Recorder) replayed: one frame per recorded
        row, in order, with its recorded encoder position. Give it to
        Gauge.run: a gauge made with the recording's own calibration and
        options (Recording.calibration(), Recording.options()) gives the
        live sheets bit for bit; other options answer "what if"."""
        fn = "Source.open_recording"
        bag = make_options(fn, options, prefixes=("source_",))
        handle = _capi.flt_source_open_recording(_path(fn, path), bag)
        return cls._wrap(handle, (), ())

    @classmethod
    def simulator(cls, sim: SimulatedLine, **options: OptionValue) -> "Source":
        """Frames rendered by `sim` (kept alive by the source), with the
        simulator's own encoder positions (source_encoder_mode "auto"), or
        the fixed step ("fixed_step") or host positions ("host"). Block ids
        count from 0."""
        fn = "Source.simulator"
        if not isinstance(sim, SimulatedLine):
            raise TypeError(f"{fn}() argument 'sim' must be a SimulatedLine, not "
                            f"{type(sim).__name__}")
        bag = make_options(fn, options, prefixes=("source_",))
        with sim._lock:
            sim_handle = sim._live()
            handle = _capi.flt_source_create_sim(sim_handle, bag)
        return cls._wrap(handle, (sim, sim_handle), (sim._lock,))

    @classmethod
    def images(cls, paths: Union[str, "os.PathLike[str]", Sequence[Any]],
               encoder_csv: Union[str, "os.PathLike[str]", None] = None,
               step: Optional[float] = None, **options: OptionValue) -> "Source":
        """A recorded image sequence (PNG, TIFF: single-channel 8 or 16 bits,
        all of one size).

        Args:
            paths: the image files in order, or a directory (its *.png,
                *.tif, *.tiff files sorted by name).
            encoder_csv: a CSV file of the positions, mm, one row per image
                ("encoder_mm" or "file name,encoder_mm"); FormatError names
                a bad line.
            step: without a CSV, the travel per image, mm (sets
                source_encoder_mode = "fixed_step" and source_encoder_step; the first
                image is at source_encoder_start).
            **options: source options (source_*), e.g. source_image_bits.

        :meth:`next` returns None after the last image.
        """
        fn = "Source.images"
        if step is not None:
            options = dict(options)
            options.setdefault("source_encoder_mode", "fixed_step")
            options["source_encoder_step"] = as_real(fn, "step", step)
        bag = make_options(fn, options, prefixes=("source_",))
        csv = None if encoder_csv is None else os.fsdecode(encoder_csv)
        if isinstance(paths, (str, bytes, os.PathLike)):
            path = os.fsdecode(paths)
            if os.path.isdir(path):
                handle = _capi.flt_source_create_image_dir(path, csv, bag)
            else:
                handle = _capi.flt_py_source_create_images([path], csv, bag)
        else:
            if not isinstance(paths, Sequence):
                raise TypeError(f"{fn}() argument 'paths' must be a directory or a "
                                f"sequence of paths, not {type(paths).__name__}")
            handle = _capi.flt_py_source_create_images(
                [os.fspath(p) if isinstance(p, os.PathLike) else p for p in paths],
                csv, bag)
        return cls._wrap(handle, (), ())

    @classmethod
    def u3v(cls, serial: Optional[str] = None, bus: Optional["U3VSimBus"] = None,
            **options: OptionValue) -> "Source":
        """Opens a USB3 Vision camera: the one with serial number `serial`
        (None: the first), on the USB bus, or on the simulated `bus` (a
        flatline.testing.U3VSimBus, kept alive by the source). Reads the
        bootstrap registers and the GenICam XML; stops a camera a killed
        process left streaming. NotFoundError for a serial that is not
        present, DeviceError when a camera cannot be opened (permissions:
        lib/sources/deploy/)."""
        fn = "Source.u3v"
        if serial is not None:
            serial = _str(fn, "serial", serial)
        _check_bus(fn, bus)
        bag = make_options(fn, options, prefixes=("source_", "u3v_"))
        if bus is None:
            return cls._wrap(_capi.flt_source_open_u3v(None, serial, bag), (), ())
        with bus._lock:
            bus_handle = bus._live()
            handle = _capi.flt_source_open_u3v(bus._transport(), serial, bag)
        return cls._wrap(handle, (bus, bus_handle), (bus._lock,), bus)

    list_cameras = staticmethod(list_cameras)

    @classmethod
    def gige(cls, camera: Optional[str] = None, **options: float) -> "Source":
        """Opens a GigE Vision camera: `camera` is its address ("a.b.c.d" or
        "a.b.c.d:port"), its serial number or user-defined name (found by a
        discovery broadcast, gige_discovery_timeout), or None for the first
        camera that answers. Takes the control privilege (kept by a
        heartbeat), reads the bootstrap registers and the GenICam file and
        negotiates the stream packet size. NotFoundError when no such camera
        answers, TimeoutError when the address does not answer, DeviceError
        when another application controls the camera."""
        fn = "Source.gige"
        if camera is not None:
            camera = _str(fn, "camera", camera)
        bag = make_options(fn, options, prefixes=("source_", "gige_"))
        return cls._wrap(_capi.flt_source_open_gige(camera, bag), (), ())

    @staticmethod
    def list_gige_cameras(address: Optional[str] = None,
                          timeout_ms: int = 1000) -> List[CameraInfo]:
        """The GigE Vision cameras that answer a discovery sent to `address`
        (a camera or a subnet's broadcast address, "a.b.c.d[:port]"), or to
        every interface's broadcast address when None, within `timeout_ms`
        (1..60000). Each has its address (pass it to :meth:`gige`)."""
        fn = "Source.list_gige_cameras"
        if address is not None:
            address = _str(fn, "address", address)
        timeout_ms = as_index(fn, "timeout_ms", timeout_ms, 1, 60000)
        handle = _capi.flt_camera_list_create_gige(address, timeout_ms)
        found = []
        for index in range(int(_capi.flt_camera_list_count(handle))):
            vendor, model, serial, speed = _capi.flt_camera_list_get(handle, index)
            found.append(CameraInfo(vendor, model, serial, int(speed),
                                    _capi.flt_camera_list_address(handle, index)))
        return found

    # -- lifetime ------------------------------------------------------------------

    def close(self) -> None:
        """Stops a streaming camera, releases it and frees the buffers now,
        then lets go of what the source borrowed. Idempotent; later calls
        raise StateError."""
        with self._lock:
            self._handle = None  # destroys the C source first...
            self._keep = ()  # ...then releases the simulator / bus it borrowed
            self._bus = None

    def __del__(self) -> None:
        # The C source must go before what it borrows, whatever order the
        # instance dictionary is cleared in.
        if getattr(self, "_handle", None) is not None:
            self._handle = None

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._handle is None

    def __enter__(self) -> "Source":
        self._live()
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def _live(self) -> _capi.flt_source:
        handle = self._handle
        if handle is None:
            raise StateError("the Source is closed")
        return handle

    def _locked(self) -> ExitStack:
        stack = ExitStack()
        stack.enter_context(self._lock)
        for lock in self._locks:
            stack.enter_context(lock)
        if self._bus is not None:
            # The simulators the bus renders now (set_frames may have changed
            # them since the source was opened), in a fixed order.
            for sim in sorted(set(self._bus._frames.values()), key=id):
                stack.enter_context(sim._lock)
        return stack

    def __repr__(self) -> str:
        if getattr(self, "_handle", None) is None:
            return "<flatline.Source closed>"
        return f"<flatline.Source {self._kind.name.lower()}>"

    @property
    def kind(self) -> SourceKind:
        """What the source reads from."""
        return self._kind

    # -- acquisition -----------------------------------------------------------------

    def start(self) -> None:
        """Starts acquisition (camera: stream set-up, buffers, AcquisitionStart;
        images: from the first image again). StateError if started."""
        with self._locked():
            _capi.flt_source_start(self._live())

    def stop(self) -> None:
        """Stops acquisition (a no-op when stopped)."""
        with self._locked():
            _capi.flt_source_stop(self._live())

    def next(self, timeout_ms: int = 1000, out: Optional[np.ndarray] = None
             ) -> Optional[Frame]:
        """The next good frame, copied (into `out` when given: a C-contiguous
        writeable (height, width) array of the frame's dtype). None after
        the last image of a sequence. TimeoutError when no good frame came
        within timeout_ms, DeviceError when the camera is gone, StateError
        before :meth:`start`. Damaged frames are dropped and counted
        (:meth:`counters`)."""
        fn = "next"
        timeout_ms = as_index(fn, "timeout_ms", timeout_ms, 0, 2**32 - 1)
        if out is not None and not isinstance(out, np.ndarray):
            raise TypeError(f"{fn}() argument 'out' must be a numpy array or None, not "
                            f"{type(out).__name__}")
        with self._locked():
            got = self._live().next_frame(timeout_ms, out)
        if got is None:
            return None
        pixels, fmt, block_id, timestamp, encoder_mm = got
        return Frame(pixels, PixelFormat(fmt), int(block_id), int(timestamp),
                     float(encoder_mm))

    def __iter__(self) -> Iterator[Frame]:
        """Frames until the end of an image sequence (:meth:`next` with its
        default timeout; a camera or simulator never ends)."""
        while True:
            frame = self.next()
            if frame is None:
                return
            yield frame

    def set_encoder(self, encoder_mm: float) -> None:
        """source_encoder_mode "host": the position the next frames carry, mm."""
        encoder_mm = as_real("set_encoder", "encoder_mm", encoder_mm)
        with self._locked():
            _capi.flt_source_set_encoder(self._live(), encoder_mm)

    def counters(self) -> Dict[str, int]:
        """Frame and channel counters since the source was created, by name:
        frames, dropped (= short + incomplete + overflow + submit_dropped +
        timeout_dropped + bad_leaders), lost (block ids skipped), timeouts,
        disconnects, bad_packets, pending_acks, stale_acks, command_retries,
        stream_recoveries..."""
        with self._locked():
            handle = self._live()
            return {name: int(_capi.flt_source_count(handle, key))
                    for name, key in _COUNTERS.items()}

    @property
    def stream_error(self) -> str:
        """Why the last frame was dropped or lost ("" if none was)."""
        with self._locked():
            return _capi.flt_source_stream_error(self._live())

    # -- cameras -------------------------------------------------------------------

    def camera_string(self, which: str) -> str:
        """A camera string: vendor, model, family, device_version,
        manufacturer_info, serial or user_name. StateError for a source that
        is not a camera."""
        key = _name("camera_string", "which", which, _CAMERA_STRINGS)
        with self._locked():
            return _capi.flt_source_camera_string(self._live(), key)

    def camera_value(self, which: str) -> int:
        """A camera value (see flt_camera_value): gencp_version, u3v_version,
        response_time_ms, control_timeout_ms, max_command_bytes,
        max_ack_bytes, sirm_address, manifest_address, xml_bytes,
        xml_zipped, speed_mbps, and after start alignment, payload_bytes,
        transfer_bytes, transfer_count, final_transfer_bytes,
        max_leader_bytes, max_trailer_bytes."""
        key = _name("camera_value", "which", which, _CAMERA_VALUES)
        with self._locked():
            return int(_capi.flt_source_camera_value(self._live(), key))

    def get_int(self, feature: str) -> int:
        """An integer GenICam feature (IntReg, Integer, Boolean, Enumeration
        value...). NotFoundError names a feature the client cannot resolve."""
        feature = _str("get_int", "feature", feature)
        with self._locked():
            return int(_capi.flt_source_get_int(self._live(), feature))

    def set_int(self, feature: str, value: int) -> None:
        """Writes an integer feature; the camera checks the range."""
        feature = _str("set_int", "feature", feature)
        value = as_index("set_int", "value", value, -2**63, 2**63 - 1)
        with self._locked():
            _capi.flt_source_set_int(self._live(), feature, value)

    def get_float(self, feature: str) -> float:
        """A float feature (Float, FloatReg; integers converted)."""
        feature = _str("get_float", "feature", feature)
        with self._locked():
            return float(_capi.flt_source_get_float(self._live(), feature))

    def set_float(self, feature: str, value: float) -> None:
        """Writes a float feature."""
        feature = _str("set_float", "feature", feature)
        value = as_real("set_float", "value", value)
        with self._locked():
            _capi.flt_source_set_float(self._live(), feature, value)

    def set_enum(self, feature: str, entry: str) -> None:
        """Sets an enumeration by entry name, e.g. ("TriggerMode", "On")."""
        feature = _str("set_enum", "feature", feature)
        entry = _str("set_enum", "entry", entry)
        with self._locked():
            _capi.flt_source_set_enum(self._live(), feature, entry)

    def execute(self, feature: str) -> None:
        """Executes a command feature, e.g. "AcquisitionStop"."""
        feature = _str("execute", "feature", feature)
        with self._locked():
            _capi.flt_source_execute(self._live(), feature)

    def map_feature(self, feature: str, address: int, length: int,
                    is_float: bool = False) -> None:
        """Gives `feature` a register (length 1, 2, 4 or 8 bytes at address,
        little-endian; an IEEE float of 4 or 8 bytes when is_float) instead
        of its XML node: for features behind formulas."""
        fn = "map_feature"
        feature = _str(fn, "feature", feature)
        address = as_index(fn, "address", address, 0, 2**64 - 1)
        length = as_index(fn, "length", length, 0, 2**32 - 1)
        with self._locked():
            _capi.flt_source_map_feature(self._live(), feature, address, length,
                                         1 if is_float else 0)

    def read_memory(self, address: int, size: int) -> bytes:
        """`size` bytes of the camera's register map from `address` (GenCP)."""
        fn = "read_memory"
        address = as_index(fn, "address", address, 0, 2**64 - 1)
        buffer = np.empty(as_index(fn, "size", size), dtype=np.uint8)
        with self._locked():
            self._live().read_memory_into(address, buffer)
        return buffer.tobytes()

    def write_memory(self, address: int, data: bytes) -> None:
        """Writes `data` to the camera's register map at `address` (GenCP)."""
        fn = "write_memory"
        address = as_index(fn, "address", address, 0, 2**64 - 1)
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise TypeError(f"{fn}() argument 'data' must be bytes, not "
                            f"{type(data).__name__}")
        array = np.frombuffer(bytes(data), dtype=np.uint8)
        with self._locked():
            self._live().write_memory_array(address, array)


def _document_options() -> None:
    text = options_doc(source_options())
    if Source.__doc__:
        Source.__doc__ = Source.__doc__.replace("{options}", text)


_document_options()
