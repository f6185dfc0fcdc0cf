# SPDX-License-Identifier: Apache-2.0
"""The exception hierarchy: one class per C status code (flatline/common.h).

Every failed C call raises a subclass of :class:`FlatlineError` carrying the C
status (``.status``, a negative int) and the library's message (``.message``,
which names the offending argument and its value). Each subclass also derives
from the built-in exception a Python programmer would catch for that kind of
failure, e.g. ``InvalidArgumentError`` is a ``ValueError``.
"""

from __future__ import annotations

import builtins

__all__ = [
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
]


class FlatlineError(Exception):
    """A libflatline call failed.

    Attributes:
        status: the C status code (``FLT_ERR_*``, a negative int).
        message: the library's explanation.
    """

    #: The status of this class; instances carry their own in ``.status``.
    STATUS: int | None = None

    def __init__(self, message: str = "", status: int | None = None) -> None:
        # One positional argument only: OSError and KeyError give a second
        # positional argument a meaning of their own.
        super().__init__(message)
        self.message = message
        self.status = self.STATUS if status is None else status

    def __str__(self) -> str:  # KeyError would quote the message
        return self.message

    def __reduce__(self):  # keeps status across pickling (multiprocessing)
        return (_from_status, (self.status, self.message))


class InvalidArgumentError(FlatlineError, ValueError):
    """An argument is out of range, NaN, or disagrees with the handle
    (``FLT_ERR_INVALID_ARGUMENT``)."""

    STATUS = -1


class OutOfMemoryError(FlatlineError, MemoryError):
    """Memory could not be allocated (``FLT_ERR_OUT_OF_MEMORY``)."""

    STATUS = -2


class StateError(FlatlineError, RuntimeError):
    """The call is not allowed in the object's current state, e.g. pull
    before any push, or use after close (``FLT_ERR_STATE``)."""

    STATUS = -3


class BufferFullError(FlatlineError, RuntimeError):
    """A fixed-capacity buffer is full; pull finished rows, push smaller
    blocks or create with a larger ``row_capacity`` (``FLT_ERR_BUFFER_FULL``)."""

    STATUS = -4


class FileError(FlatlineError, OSError):
    """A file could not be opened, read or written (``FLT_ERR_IO``)."""

    STATUS = -5


class FormatError(FlatlineError, ValueError):
    """A file or packet is malformed; the message names the field
    (``FLT_ERR_FORMAT``). A ``ValueError``: the bytes were read, their
    content is wrong."""

    STATUS = -6


class DeviceError(FlatlineError, OSError):
    """A camera or transport failed (``FLT_ERR_DEVICE``)."""

    STATUS = -7


class TimeoutError(FlatlineError, builtins.TimeoutError):
    """A device did not answer in time (``FLT_ERR_TIMEOUT``). Also a
    built-in ``TimeoutError``."""

    STATUS = -8


class NotFoundError(FlatlineError, KeyError):
    """Something named (an option, a device, a feature) does not exist
    (``FLT_ERR_NOT_FOUND``). A ``KeyError``, hence a ``LookupError``."""

    STATUS = -9


class NumericError(FlatlineError, ArithmeticError):
    """A singular system or a failed estimate (``FLT_ERR_NUMERIC``)."""

    STATUS = -10


class InternalError(FlatlineError, RuntimeError):
    """A bug in libflatline; please report it with the message
    (``FLT_ERR_INTERNAL``)."""

    STATUS = -99


_BY_STATUS: dict[int, type[FlatlineError]] = {
    cls.STATUS: cls
    for cls in (
        InvalidArgumentError,
        OutOfMemoryError,
        StateError,
        BufferFullError,
        FileError,
        FormatError,
        DeviceError,
        TimeoutError,
        NotFoundError,
        NumericError,
        InternalError,
    )
}

# Tracebacks and reprs name the public module (flatline.FileError), where a
# user imports and catches them, not this private one.
for _cls in (FlatlineError, *_BY_STATUS.values()):
    _cls.__module__ = "flatline"


def _from_status(status: int, message: str) -> FlatlineError:
    """The exception for a C status (called by the extension on failure).
    A code this version does not know gives a plain FlatlineError."""
    cls = _BY_STATUS.get(status, FlatlineError)
    return cls(message, status)
