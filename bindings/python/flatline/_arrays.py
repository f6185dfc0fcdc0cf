# SPDX-License-Identifier: Apache-2.0
"""Conversion of array-like arguments to what the C API reads.

The C API takes C-contiguous, native-endian float64 (and uint8 masks).
Arrays that already are that pass through without a copy; anything else that
numpy can cast *safely* (ints, float32, bool, lists...) is converted; the
rest (complex, strings, objects, NaN-free but lossy casts) is a TypeError, and
a wrong number of dimensions or a wrong length is a ValueError. Every message
names the argument.
"""

from __future__ import annotations

import numbers
from typing import Any, Optional, Tuple

import numpy as np

_F64 = np.dtype(np.float64)
_U8 = np.dtype(np.uint8)


def _as_array(function: str, name: str, value: Any) -> np.ndarray:
    if value is None:
        raise TypeError(f"{function}() argument '{name}' must be array-like, not None")
    try:
        array = np.asanyarray(value)
    except Exception as exc:  # ragged lists, objects numpy refuses
        raise TypeError(
            f"{function}() argument '{name}' is not array-like: {exc}"
        ) from None
    if isinstance(array, np.ma.MaskedArray):
        raise TypeError(
            f"{function}() argument '{name}' is a masked array; pass the data "
            f"and use the 'valid' argument for the mask"
        )
    return array


def as_float64(function: str, name: str, value: Any, ndim: int) -> np.ndarray:
    """`value` as a C-contiguous native float64 array of `ndim` dimensions."""
    array = _as_array(function, name, value)
    if not np.can_cast(array.dtype, _F64, casting="safe"):
        raise TypeError(
            f"{function}() argument '{name}' has dtype {array.dtype}, which "
            f"cannot be converted to float64 without loss"
        )
    if array.ndim != ndim:
        raise ValueError(
            f"{function}() argument '{name}' must have {ndim} dimension"
            f"{'s' if ndim != 1 else ''}, got shape {array.shape}"
        )
    # No copy when it already is C-contiguous, aligned, native float64.
    return np.require(array, dtype=_F64, requirements=("C", "A"))


def as_mask(function: str, name: str, value: Any, ndim: int) -> np.ndarray:
    """`value` as a C-contiguous uint8 array (non-zero = valid). bool arrays
    are reinterpreted without a copy; integer arrays are compared with 0."""
    array = _as_array(function, name, value)
    if array.ndim != ndim:
        raise ValueError(
            f"{function}() argument '{name}' must have {ndim} dimension"
            f"{'s' if ndim != 1 else ''}, got shape {array.shape}"
        )
    if array.dtype == np.bool_:
        return np.require(array, requirements=("C", "A")).view(_U8)
    if array.dtype.kind in "iu":
        return np.require(array != 0, requirements=("C", "A")).view(_U8)
    raise TypeError(
        f"{function}() argument '{name}' must be a bool (or integer) mask, "
        f"got dtype {array.dtype}"
    )


def check_shape(function: str, name: str, array: np.ndarray,
                expected: Tuple[int, ...], against: str) -> None:
    if array.shape != expected:
        raise ValueError(
            f"{function}() argument '{name}' has shape {array.shape}, but "
            f"{against} requires {expected}"
        )


# numpy.i has no optional arrays; the unmasked C calls get this placeholder
# and a flag that tells the helper to pass NULL.
NO_MASK = np.ones((1, 1), dtype=np.uint8)


def block(function: str, s: Any, height: Any, slope: Any,
          valid: Optional[Any]) -> Tuple[np.ndarray, np.ndarray, np.ndarray,
                                         np.ndarray, int]:
    """Validates one block of rows: s (N,), height/slope/valid (N, K).
    Returns (s, height, slope, mask, masked) ready for the C helpers."""
    height = as_float64(function, "height", height, 2)
    rows, fibers = height.shape
    s = as_float64(function, "s", s, 1)
    check_shape(function, "s", s, (rows,), "height.shape[0]")
    slope = as_float64(function, "slope", slope, 2)
    check_shape(function, "slope", slope, (rows, fibers), "height.shape")
    if valid is None:
        return s, height, slope, NO_MASK, 0
    mask = as_mask(function, "valid", valid, 2)
    check_shape(function, "valid", mask, (rows, fibers), "height.shape")
    return s, height, slope, mask, 1


def as_points(function: str, name: str, value: Any) -> np.ndarray:
    """`value` as a C-contiguous float64 (N, 2) array of points: (u, v) px
    or (x, z) mm per row."""
    points = as_float64(function, name, value, 2)
    if points.shape[1] != 2:
        raise ValueError(
            f"{function}() argument '{name}' must have shape (N, 2), got "
            f"{points.shape}"
        )
    return points


def as_index(function: str, name: str, value: Any, lowest: int = 0,
             highest: Optional[int] = None) -> int:
    """An integer argument (not a bool) in [lowest, highest] as a Python int:
    TypeError for another type, ValueError outside the range."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(
            f"{function}() argument '{name}' must be an int, not {type(value).__name__}"
        )
    value = int(value)
    if value < lowest or (highest is not None and value > highest):
        bound = f">= {lowest}" if highest is None else f"in [{lowest}, {highest}]"
        raise ValueError(f"{function}() argument '{name}' must be {bound}, got {value}")
    return value


def as_real(function: str, name: str, value: Any) -> float:
    """A real-number argument (not a bool) as a float; NaN and infinities are
    passed on for the library to judge."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(
            f"{function}() argument '{name}' must be a real number, not "
            f"{type(value).__name__}"
        )
    try:
        return float(value)
    except OverflowError:  # an int like 10**400
        text = str(value)
        text = text[:60] + "..." if len(text) > 60 else text
        raise ValueError(
            f"{function}() argument '{name}' = {text} is beyond the range of a double"
        ) from None
