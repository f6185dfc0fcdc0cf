# SPDX-License-Identifier: Apache-2.0
"""The offline view of a camera description (flatline/genicam.h).

A GenICam description (the XML a USB3 Vision or GigE Vision camera
delivers, zipped or not) lists the camera's features and how each maps to
the camera's registers. :class:`CameraDescription` loads one without a
camera, lists its features, and evaluates them for register contents you
put into its memory image, the way the library's camera clients do on a
real camera:

    >>> from flatline.genicam import CameraDescription
    >>> camera = CameraDescription("camera.xml")
    >>> camera.set_memory(0x81084, (1920).to_bytes(4, "little"))
    >>> camera.get("Width")
    1920
    >>> camera.register("Width")
    Register(address=528516, length=4, lsb=0, msb=31, big_endian=False)

Reads ignore the access mode (they show what the registers hold);
:meth:`CameraDescription.access` says whether a camera would let a feature
be read or written. Writes honour it and land in the memory image.
"""

from __future__ import annotations

import enum
import os
import threading
from typing import Any, Iterator, List, NamedTuple, Tuple, Union

from . import capi as _capi
from ._arrays import as_index
from ._errors import NotFoundError

__all__ = [
    "FeatureType",
    "Access",
    "Feature",
    "Register",
    "Flags",
    "EnumEntry",
    "CameraDescription",
]


class FeatureType(enum.IntEnum):
    """The interface a feature offers."""

    INTEGER = _capi.FLT_GENICAM_INTEGER  #: Integer, IntReg, MaskedIntReg, StructEntry, IntConverter, IntSwissKnife
    FLOAT = _capi.FLT_GENICAM_FLOAT  #: Float, FloatReg, Converter, SwissKnife
    ENUMERATION = _capi.FLT_GENICAM_ENUMERATION  #: an entry name over an integer
    BOOLEAN = _capi.FLT_GENICAM_BOOLEAN
    COMMAND = _capi.FLT_GENICAM_COMMAND
    STRING = _capi.FLT_GENICAM_STRING  #: String, StringReg
    REGISTER = _capi.FLT_GENICAM_REGISTER  #: raw bytes
    CATEGORY = _capi.FLT_GENICAM_CATEGORY  #: a node of the feature tree (no value)


class Access(enum.IntEnum):
    """A feature's access mode for the current register contents."""

    NOT_IMPLEMENTED = _capi.FLT_GENICAM_NOT_IMPLEMENTED
    NOT_AVAILABLE = _capi.FLT_GENICAM_NOT_AVAILABLE
    WRITE_ONLY = _capi.FLT_GENICAM_WRITE_ONLY
    READ_ONLY = _capi.FLT_GENICAM_READ_ONLY
    READ_WRITE = _capi.FLT_GENICAM_READ_WRITE


class Feature(NamedTuple):
    """A feature as the description declares it."""

    name: str
    type: FeatureType
    kind: str  #: the XML element: "IntReg", "Converter", "StructEntry", ...
    unit: str  #: its Unit ("us", "dB"), "" if none


class Register(NamedTuple):
    """The register holding a feature's value."""

    address: int  #: bytes
    length: int  #: bytes
    lsb: int  #: lowest bit of the value (0 = the register value's least significant bit)
    msb: int  #: highest bit of the value
    big_endian: bool


class Flags(NamedTuple):
    """A feature's own pIsImplemented, pIsAvailable and pIsLocked, evaluated now."""

    implemented: bool
    available: bool
    locked: bool


class EnumEntry(NamedTuple):
    """An entry of an enumeration."""

    name: str
    value: int
    available: bool  #: implemented and available now


PathOrBytes = Union[str, "os.PathLike[str]", bytes, bytearray, memoryview]


def _feature(function: str, name: Any) -> str:
    if not isinstance(name, str):
        raise TypeError(f"{function}() argument 'feature' must be a str, not "
                        f"{type(name).__name__}")
    return name


class CameraDescription:
    """A loaded GenICam description with a memory image of its registers.

    ``source`` is a file name (XML or a ZIP archive holding it) or the
    file's contents as bytes. A handle must not be used from two threads at
    once; this class serialises its calls with a lock.
    """

    def __init__(self, source: PathOrBytes) -> None:
        self._lock = threading.Lock()
        if isinstance(source, (bytes, bytearray, memoryview)):
            self._g = _capi.flt_py_genicam_load_memory(source)
        elif isinstance(source, (str, os.PathLike)):
            self._g = _capi.flt_genicam_load(os.fspath(source))
        else:
            raise TypeError("CameraDescription() argument 'source' must be a path or bytes, "
                            f"not {type(source).__name__}")
        count = _capi.flt_genicam_feature_count(self._g)
        self._names = [_capi.flt_genicam_feature_name(self._g, i) for i in range(count)]

    # ---- the description itself ------------------------------------------

    @property
    def vendor(self) -> str:
        """VendorName of the description."""
        return _capi.flt_genicam_get_text(self._g, _capi.FLT_GENICAM_VENDOR_NAME)

    @property
    def model(self) -> str:
        """ModelName of the description."""
        return _capi.flt_genicam_get_text(self._g, _capi.FLT_GENICAM_MODEL_NAME)

    @property
    def schema_version(self) -> str:
        """The GenApi schema version, "major.minor.subminor" ("" if absent)."""
        return _capi.flt_genicam_get_text(self._g, _capi.FLT_GENICAM_SCHEMA_VERSION)

    def __len__(self) -> int:
        return len(self._names)

    def __iter__(self) -> Iterator[str]:
        return iter(list(self._names))

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self._names

    def features(self) -> List[Feature]:
        """Every feature (value and command nodes) in document order."""
        with self._lock:
            out = []
            for name in self._names:
                type_, kind, unit = _capi.flt_genicam_feature_info(self._g, name)
                out.append(Feature(name, FeatureType(type_), kind, unit))
            return out

    def feature(self, name: str) -> Feature:
        """One feature's declaration (NotFoundError if the description lacks it)."""
        _feature("feature", name)
        with self._lock:
            type_, kind, unit = _capi.flt_genicam_feature_info(self._g, name)
        return Feature(name, FeatureType(type_), kind, unit)

    def category(self, name: str = "Root") -> List[str]:
        """The entries of a category of the feature tree, in the file's
        order: features and sub-categories (:meth:`feature` tells them apart:
        ``FeatureType.CATEGORY``). The tree starts at "Root". An entry may
        name a node the file lacks. NotFoundError for a name that is no
        category."""
        _feature("category", name)
        out: List[str] = []
        with self._lock:
            while True:
                try:
                    out.append(_capi.flt_genicam_category_entry(self._g, name, len(out)))
                except NotFoundError:
                    # past the last entry, or no such category (an empty
                    # one is still a category)
                    if not out and not self._is_category(name):
                        raise
                    return out

    def _is_category(self, name: str) -> bool:
        try:
            type_, _, _ = _capi.flt_genicam_feature_info(self._g, name)
        except NotFoundError:
            return False
        return bool(type_ == FeatureType.CATEGORY)

    def tree(self, name: str = "Root") -> Iterator[Tuple[int, str]]:
        """Walks the feature tree from category ``name`` depth first:
        (depth, entry) for every entry below it (depth 0 for its own
        entries); a category is entered once (a file that lists a category
        inside itself does not loop)."""
        seen = {name}

        def walk(category: str, depth: int) -> Iterator[Tuple[int, str]]:
            for entry in self.category(category):
                yield depth, entry
                if entry in seen:
                    continue
                try:
                    is_category = self.feature(entry).type == FeatureType.CATEGORY
                except NotFoundError:
                    is_category = False
                if is_category:
                    seen.add(entry)
                    yield from walk(entry, depth + 1)

        return walk(name, 0)

    # ---- register contents -------------------------------------------------

    def set_memory(self, address: int, data: Union[bytes, bytearray, memoryview]) -> None:
        """Puts ``data`` (bytes in the device's memory order) at ``address``."""
        address = as_index("set_memory", "address", address, 0, 2**64 - 1)
        with self._lock:
            self._g.put_memory(address, data)

    def get_memory(self, address: int, count: int) -> bytes:
        """``count`` bytes of the memory image (NotFoundError for a byte it lacks)."""
        address = as_index("get_memory", "address", address, 0, 2**64 - 1)
        count = as_index("get_memory", "count", count, 0, 2**64 - 1)
        with self._lock:
            return self._g.fetch_memory(address, count)

    def clear_memory(self) -> None:
        """Empties the memory image."""
        with self._lock:
            _capi.flt_genicam_clear_memory(self._g)

    # ---- evaluation ------------------------------------------------------------

    def access(self, name: str) -> Access:
        """The access mode for the current registers."""
        _feature("access", name)
        with self._lock:
            return Access(_capi.flt_genicam_get_access(self._g, name))

    def flags(self, name: str) -> Flags:
        """The feature's own pIsImplemented, pIsAvailable, pIsLocked."""
        _feature("flags", name)
        with self._lock:
            return Flags(*_capi.flt_genicam_get_flags(self._g, name))

    def register(self, name: str) -> Register:
        """The register behind the feature (NotFoundError when its value is a
        formula of several nodes or a constant)."""
        _feature("register", name)
        with self._lock:
            return Register(*_capi.flt_genicam_register(self._g, name))

    def get(self, name: str) -> Union[int, float, str, bool]:
        """The value, typed by the feature: int, float, str (strings and
        enumeration entries) or bool. A command or a raw register has none
        (InvalidArgumentError)."""
        type_ = self.feature(name).type
        with self._lock:
            if type_ == FeatureType.INTEGER:
                return _capi.flt_genicam_get_int(self._g, name)
            if type_ == FeatureType.BOOLEAN:
                return bool(_capi.flt_genicam_get_int(self._g, name))
            if type_ == FeatureType.FLOAT:
                return _capi.flt_genicam_get_float(self._g, name)
            return _capi.flt_genicam_get_string(self._g, name)

    def get_int(self, name: str) -> int:
        """The integer value (of an enumeration: the entry's integer)."""
        _feature("get_int", name)
        with self._lock:
            return _capi.flt_genicam_get_int(self._g, name)

    def get_float(self, name: str) -> float:
        """The value as a float."""
        _feature("get_float", name)
        with self._lock:
            return _capi.flt_genicam_get_float(self._g, name)

    def get_string(self, name: str) -> str:
        """A string feature's value, or an enumeration's entry name."""
        _feature("get_string", name)
        with self._lock:
            return _capi.flt_genicam_get_string(self._g, name)

    def int_bounds(self, name: str) -> Tuple[int, int, int]:
        """(min, max, inc) of an integer feature; -2**63 / 2**63-1 / 1 without one."""
        _feature("int_bounds", name)
        with self._lock:
            return tuple(_capi.flt_genicam_int_bounds(self._g, name))  # type: ignore[return-value]

    def float_bounds(self, name: str) -> Tuple[float, float]:
        """(min, max) of a float feature; -/+ the largest double without one."""
        _feature("float_bounds", name)
        with self._lock:
            return tuple(_capi.flt_genicam_float_bounds(self._g, name))  # type: ignore[return-value]

    def entries(self, name: str) -> List[EnumEntry]:
        """An enumeration's entries, with their availability now."""
        _feature("entries", name)
        with self._lock:
            count = _capi.flt_genicam_enum_count(self._g, name)
            return [EnumEntry(*_capi.flt_genicam_enum_entry(self._g, name, i))
                    for i in range(count)]

    # ---- writes -------------------------------------------------------------------

    def set(self, name: str, value: Union[int, float, str, bool]) -> None:
        """Writes a feature: a str sets a string or an enumeration entry, a
        bool or int an integer, enumeration or boolean, a float a float."""
        _feature("set", name)
        with self._lock:
            if isinstance(value, str):
                _capi.flt_genicam_set_string(self._g, name, value)
            elif isinstance(value, (bool, int)):
                _capi.flt_genicam_set_int(self._g, name,
                                          as_index("set", "value", int(value), -2**63, 2**63 - 1))
            elif isinstance(value, float):
                _capi.flt_genicam_set_float(self._g, name, value)
            else:
                raise TypeError("set() argument 'value' must be an int, float, str or bool, "
                                f"not {type(value).__name__}")

    def execute(self, name: str) -> None:
        """Executes a command (writes its command value)."""
        _feature("execute", name)
        with self._lock:
            _capi.flt_genicam_execute(self._g, name)

    def __repr__(self) -> str:
        return (f"CameraDescription(vendor={self.vendor!r}, model={self.model!r}, "
                f"{len(self._names)} features)")
