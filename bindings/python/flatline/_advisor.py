# SPDX-License-Identifier: Apache-2.0
"""The leveler advisor (flatline/advisor.h): what to change on the leveler
after each sheet. A leveler's actuators and its influence matrix G (zone
I-Units per actuator unit) come from the vendor's file (Advisor.load) or an
array, or G is identified from logged steps (Advisor.identify); advise()
proposes the change of the settings within every actuator's range and step
limit."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, Optional, Union

import numpy as np

from . import capi as _capi
from ._arrays import as_float64
from ._calib import PathLike, _path
from ._options import OptionValue, make_options, prefixed_options

__all__ = ["Actuator", "Advice", "Advisor", "AdvisorFit", "MIN_R_SQUARED", "advisor_options"]

#: The smallest R^2 of an accepted identification.
MIN_R_SQUARED: float = _capi.FLT_ADVISOR_MIN_R_SQUARED


def advisor_options() -> Dict[str, float]:
    """The advisor's options (advisor_*) with their C defaults."""
    return {name: info.default for name, info in prefixed_options("advisor_").items()}


@dataclass(frozen=True)
class Actuator:
    """One actuator of the leveler: its setting lies in [min, max] and moves
    by at most `step` per advice (in its own unit)."""

    name: str
    unit: str
    min: float
    max: float
    step: float


@dataclass(frozen=True)
class AdvisorFit:
    """The model's quality: R^2 and RMS residual (I-Units) of the last
    identification over its steps; 1, 0, 0 for a G given by the vendor;
    NaN before any G or after a refusal for too few or degenerate steps."""

    r_squared: float
    rms_i_units: float
    steps: int


@dataclass(frozen=True)
class Advice:
    """An advice: the change of every actuator's setting, the zone profile
    expected with it (I-Units) and the confidence in [0, 1]."""

    delta: np.ndarray
    predicted: np.ndarray
    confidence: float


class Advisor:
    """A leveler advisor of `zones` zones and `actuators` actuators (or
    from a leveler file: :meth:`load`). Describe every actuator
    (:meth:`set_actuator`) and give or identify G before :meth:`advise`.
    Options by their C names: advisor_damping (lambda relative to the mean
    squared effect of a unit step, default 0.01), advisor_gain (the share
    of the deviation one advice sets out to remove, default 0.5). Not for
    two threads at once."""

    def __init__(self, zones: int, actuators: int, *, _handle: Any = None,
                 **options: OptionValue) -> None:
        if _handle is not None:
            self._handle = _handle
        else:
            bag = make_options("Advisor", options, prefixes=("advisor_",))
            for name, value in (("zones", zones), ("actuators", actuators)):
                if not isinstance(value, int) or isinstance(value, bool):
                    raise TypeError(f"Advisor() argument '{name}' must be an int, "
                                    f"not {type(value).__name__}")
                if value < 1:
                    raise ValueError(f"Advisor() argument '{name}' = {value} must be >= 1")
            self._handle = _capi.flt_advisor_create(zones, actuators, bag)
        self._zones, self._actuators = _capi.flt_advisor_size(self._handle)

    @classmethod
    def load(cls, path: PathLike, **options: OptionValue) -> "Advisor":
        """Reads a leveler file ("flatline-leveler" version 1, UTF-8 JSON;
        flatline/advisor.h, "Leveler files"). Raises FileError (an OSError)
        if it cannot be read, FormatError (a ValueError) naming the field
        and its line if it is malformed."""
        bag = make_options("load", options, prefixes=("advisor_",))
        return cls(0, 0, _handle=_capi.flt_advisor_load(_path("load", path), bag))

    @classmethod
    def loads(cls, text: Union[str, bytes], **options: OptionValue) -> "Advisor":
        """The same as :meth:`load` from the text of a file."""
        if isinstance(text, (bytes, bytearray, memoryview)):
            try:
                text = bytes(text).decode("utf-8")
            except UnicodeDecodeError as exc:
                raise ValueError(f"loads() argument 'text' is not UTF-8: {exc}") from None
        elif not isinstance(text, str):
            raise TypeError(
                f"loads() argument 'text' must be str or bytes, not {type(text).__name__}"
            )
        bag = make_options("loads", options, prefixes=("advisor_",))
        return cls(0, 0, _handle=_capi.flt_advisor_load_text(text, bag))

    @property
    def zones(self) -> int:
        """The zone profile's length."""
        return int(self._zones)

    @property
    def actuators(self) -> int:
        """The number of actuators."""
        return int(self._actuators)

    def set_actuator(self, index: int, name: str, unit: str, min: float, max: float,
                     step: float) -> None:
        """Describes actuator `index`: its name (1..63 bytes), unit, range
        [min, max] and step limit (> 0)."""
        _capi.flt_advisor_set_actuator(self._handle, int(index), str(name), str(unit),
                                       float(min), float(max), float(step))

    def actuator(self, index: int) -> Actuator:
        """Actuator `index` as described (name "" and NaNs before)."""
        name, unit, lo, hi, step = _capi.flt_advisor_actuator(self._handle, int(index))
        return Actuator(name, unit, lo, hi, step)

    @property
    def influence(self) -> np.ndarray:
        """G, (zones, actuators), I-Units per unit (a copy)."""
        g = np.empty((self.zones, self.actuators))
        self._handle.influence_into(g)
        return g

    @influence.setter
    def influence(self, g: Any) -> None:
        self._handle.set_influence_array(as_float64("influence", "g", g, 2))

    def set_target(self, target: Optional[Any]) -> None:
        """The zone profile to aim at (zones,), I-Units; None: flat."""
        if target is None:
            self._handle.set_target_array(0, np.zeros(0))
        else:
            self._handle.set_target_array(1, as_float64("set_target", "target", target, 1))

    def identify(self, delta_u: Any, delta_p: Any, ridge: float = 0.0) -> AdvisorFit:
        """Identifies G from logged steps: delta_u (steps, actuators) the
        setting changes, delta_p (steps, zones) the profile changes they
        caused. Raises NumericError (an ArithmeticError) when the
        identification is refused (too few or degenerate steps, R^2 below
        MIN_R_SQUARED); advise() then refuses too."""
        fn = "identify"
        du = as_float64(fn, "delta_u", delta_u, 2)
        dp = as_float64(fn, "delta_p", delta_p, 2)
        self._handle.identify_arrays(du, dp, float(ridge))
        return self.fit

    @property
    def fit(self) -> AdvisorFit:
        """The quality of the model (see :class:`AdvisorFit`)."""
        r2, rms, steps = _capi.flt_advisor_fit(self._handle)
        return AdvisorFit(r2, rms, int(steps))

    def advise(self, profile: Any, settings_sheet: Any, settings_now: Any = None) -> Advice:
        """The change of the settings for a sheet's measured zone profile
        (zones,), the settings that sheet went through (actuators,) and the
        settings now (actuators,; default: the sheet's). Raises StateError
        when an actuator is not described, no G is set or the last
        identification was refused."""
        fn = "advise"
        p = as_float64(fn, "profile", profile, 1)
        us = as_float64(fn, "settings_sheet", settings_sheet, 1)
        un = us if settings_now is None else as_float64(fn, "settings_now", settings_now, 1)
        delta = np.empty(self.actuators)
        predicted = np.empty(self.zones)
        confidence = self._handle.advise_arrays(p, us, un, delta, predicted)
        return Advice(delta, predicted, float(confidence))

    def __repr__(self) -> str:
        return f"<flatline.Advisor: {self.zones} zones, {self.actuators} actuators>"
