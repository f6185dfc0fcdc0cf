# SPDX-License-Identifier: Apache-2.0
"""Pixel formats of camera frames (flatline/extractor.h), shared by the
extractor and the simulated sensor."""

from __future__ import annotations

import enum

import numpy as np

from . import capi as _capi

__all__ = ["PixelFormat"]


class PixelFormat(enum.IntEnum):
    """Pixel formats of frames; the value is the number of significant bits.
    Mono8 frames are uint8 arrays; Mono10, Mono12 and Mono16 frames are
    uint16 arrays with the data in the low bits (GenICam unpacked formats)."""

    MONO8 = _capi.FLT_PIXEL_MONO8
    MONO10 = _capi.FLT_PIXEL_MONO10
    MONO12 = _capi.FLT_PIXEL_MONO12
    MONO16 = _capi.FLT_PIXEL_MONO16

    @property
    def dtype(self) -> np.dtype:
        """The numpy dtype of a frame of this format."""
        return np.dtype(np.uint8 if self is PixelFormat.MONO8 else np.uint16)

    @property
    def full_scale(self) -> int:
        """The largest pixel value, 2^bits - 1."""
        return (1 << int(self)) - 1


def check_one_channel(function: str, frame: np.ndarray) -> None:
    """A colour frame (height, width, 3 or 4) is refused with what to do:
    the lasers' lines are measured on one channel."""
    if frame.ndim == 3 and frame.shape[2] in (3, 4):
        raise ValueError(
            f"{function}() argument 'frame' has shape {frame.shape}: {frame.shape[2]} "
            f"channels; pass one channel (frame[:, :, 0], or the channel of the lasers' "
            f"colour), a (height, width) array")
