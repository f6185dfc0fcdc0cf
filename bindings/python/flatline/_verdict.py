# SPDX-License-Identifier: Apache-2.0
"""Verdicts (flatline/verdict.h): a sheet against the flatness tolerances
the user delivers to. Rule sets are JSON data (ToleranceRules.load); a Verdict
judges one sheet at a time: pass or fail per rule, the worst value, where
it is and its margin."""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from typing import Any, Iterator, List, Optional, Tuple, Union

import numpy as np

from . import capi as _capi
from ._arrays import as_float64, as_mask
from ._calib import PathLike, _path

__all__ = [
    "Measure",
    "VerdictState",
    "ToleranceRule",
    "RuleResult",
    "ToleranceRules",
    "Verdict",
    "straightedge_deviation",
]

class Measure(enum.IntEnum):
    """What a rule measures (flt_measure)."""

    STRAIGHTEDGE_ALONG = _capi.FLT_MEASURE_STRAIGHTEDGE_ALONG  #: along every fiber, mm
    STRAIGHTEDGE_ACROSS = _capi.FLT_MEASURE_STRAIGHTEDGE_ACROSS  #: across every row, mm
    ZONE_I_UNITS = _capi.FLT_MEASURE_ZONE_I_UNITS  #: the largest zone I-Units
    WAVE_STEEPNESS = _capi.FLT_MEASURE_WAVE_STEEPNESS  #: %
    WAVE_HEIGHT = _capi.FLT_MEASURE_WAVE_HEIGHT  #: mm, peak to peak
    BOW = _capi.FLT_MEASURE_BOW  #: mm, its magnitude judged
    CROSSBOW = _capi.FLT_MEASURE_CROSSBOW  #: mm, its magnitude judged


class VerdictState(enum.IntEnum):
    """A rule's outcome (flt_verdict_state)."""

    PASS = _capi.FLT_VERDICT_PASS  #: the worst value is at most the limit
    FAIL = _capi.FLT_VERDICT_FAIL  #: the worst value exceeds the limit
    NO_BAND = _capi.FLT_VERDICT_NO_BAND  #: no band covers the sheet's thickness and width
    NOT_MEASURED = _capi.FLT_VERDICT_NOT_MEASURED  #: no map, or the value was not given
    #: the gauge's sheet is incomplete; also a whole sheet's verdict
    #: (Sheet.verdict_state) when a rule could not judge it
    NOT_JUDGED = _capi.FLT_VERDICT_NOT_JUDGED


@dataclass(frozen=True)
class ToleranceRule:
    """One rule of a rule set."""

    name: str
    measure: Measure
    length_mm: float  #: the straightedge's length; 0 for other measures


@dataclass(frozen=True)
class RuleResult:
    """One rule's verdict on the last sheet. worst, margin, x_mm and s_mm
    are NaN unless the state is PASS or FAIL; limit is NaN with NO_BAND."""

    rule: ToleranceRule
    state: VerdictState
    worst: float  #: the worst value (the measure's unit)
    limit: float  #: the limit of the band that applies
    margin: float  #: limit - worst: >= 0 passes
    x_mm: float  #: where the worst value is, across the strip
    s_mm: float  #: ... and along it
    band: int  #: the band's index in the rule file; -1 with NO_BAND

    @property
    def passed(self) -> bool:
        """True when the rule applied and passed."""
        return self.state == VerdictState.PASS


def _rule_list(handle: Any) -> List[ToleranceRule]:
    """The rules of a flt_rules handle (owned or a sheet's)."""
    out = []
    for i in range(int(_capi.flt_rules_count(handle))):
        name, measure, length = _capi.flt_rules_rule(handle, i)
        out.append(ToleranceRule(name, Measure(measure), length))
    return out


def _results(handle: Any, rules: List[ToleranceRule]) -> List[RuleResult]:
    """The results of a flt_verdict handle (owned or a sheet's), in rule
    order."""
    out = []
    for i, rule in enumerate(rules):
        def get(key: int) -> float:
            return float(_capi.flt_verdict_get(handle, i, key))
        out.append(RuleResult(
            rule=rule,
            state=VerdictState(int(get(_capi.FLT_VERDICT_STATE))),
            worst=get(_capi.FLT_VERDICT_WORST),
            limit=get(_capi.FLT_VERDICT_LIMIT),
            margin=get(_capi.FLT_VERDICT_MARGIN),
            x_mm=get(_capi.FLT_VERDICT_X),
            s_mm=get(_capi.FLT_VERDICT_S),
            band=int(get(_capi.FLT_VERDICT_BAND)),
        ))
    return out


def straightedge_deviation(positions: Any, heights: Any, length_mm: float) -> Tuple[float, float]:
    """The straightedge deviation of one profile: the largest gap between
    the profile and a straightedge of `length_mm` resting on it on two
    contacts (flatline/verdict.h, "Measures"), and the position of its
    deepest point. positions (n,) strictly increasing, mm; heights (n,) mm
    (NaN = not measured, left out). Raises NotFoundError when fewer than 2
    samples are measured."""
    fn = "straightedge_deviation"
    p = as_float64(fn, "positions", positions, 1)
    z = as_float64(fn, "heights", heights, 1)
    deviation, at = _capi.flt_py_straightedge_profile(p, z, float(length_mm))
    return deviation, at


class ToleranceRules:
    """A rule set of flatness tolerances, read from a rule file (UTF-8
    JSON, "flatline-tolerances" version 1; flatline/verdict.h, "Rule
    files"). Read-only: threads may share it."""

    def __init__(self, handle: Any) -> None:
        self._handle = handle

    @classmethod
    def load(cls, path: PathLike) -> "ToleranceRules":
        """Reads a rule file. Raises FileError (an OSError) if it cannot be
        read, FormatError (a ValueError) if it is malformed, with a message
        naming the field and its line."""
        return cls(_capi.flt_rules_load(_path("load", path)))

    @classmethod
    def loads(cls, text: Union[str, bytes]) -> "ToleranceRules":
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
        return cls(_capi.flt_rules_load_text(text))

    def __len__(self) -> int:
        return int(_capi.flt_rules_count(self._handle))

    def __getitem__(self, index: int) -> ToleranceRule:
        if not isinstance(index, int) or isinstance(index, bool):
            raise TypeError(f"rule index must be an int, not {type(index).__name__}")
        n = len(self)
        if index < 0:
            index += n
        if not 0 <= index < n:
            raise IndexError(f"rule index {index} is outside 0..{n - 1}")
        name, measure, length = _capi.flt_rules_rule(self._handle, index)
        return ToleranceRule(name, Measure(measure), length)

    def __iter__(self) -> Iterator["ToleranceRule"]:
        return (self[i] for i in range(len(self)))

    def __repr__(self) -> str:
        return f"<flatline.ToleranceRules: {len(self)} rules>"


class Verdict:
    """Judges sheets against a rule set (it keeps its own copy). Give the
    flatness measures with :meth:`set_measure`, then :meth:`evaluate` a
    sheet's height map. Not for two threads at once."""

    def __init__(self, rules: ToleranceRules) -> None:
        if not isinstance(rules, ToleranceRules):
            raise TypeError(f"Verdict() argument 'rules' must be ToleranceRules, not {type(rules).__name__}")
        self._rules = _rule_list(rules._handle)
        self._handle = _capi.flt_verdict_create(rules._handle)

    def set_measure(self, measure: Measure, value: float, x_mm: float = 0.0,
                    s_mm: float = 0.0) -> None:
        """One of the flatness measures (not a straightedge) and where it
        is; it stays until given again. NaN (or None) = not measured."""
        m = int(measure)
        v = math.nan if value is None else float(value)
        _capi.flt_verdict_set_measure(self._handle, m, v, float(x_mm), float(s_mm))

    def evaluate(self, thickness_mm: float, width_mm: float, s: Any = None, x: Any = None,
                 z: Any = None, flags: Any = None) -> List[RuleResult]:
        """Judges one sheet: its thickness and width (mm) choose each
        rule's band; s (rows,), x (fibers,) and z (rows, fibers) are its
        height map (mm; NaN = not measured; None for all three: no map, the
        straightedge rules are NOT_MEASURED), flags (rows, fibers) its
        FLT_FLAG_* bits (FLAG_NO_DATA samples are left out). Returns the
        results in rule order."""
        fn = "evaluate"
        if s is None and x is None and z is None:
            empty1 = np.zeros(0)
            empty2 = np.zeros((0, 0))
            self._handle.evaluate_arrays(float(thickness_mm), float(width_mm), 0, empty1,
                                         empty1, empty2, 0, np.zeros((0, 0), np.uint8))
        else:
            s_a = as_float64(fn, "s", s, 1)
            x_a = as_float64(fn, "x", x, 1)
            z_a = as_float64(fn, "z", z, 2)
            if flags is None:
                f_a = np.zeros((0, 0), np.uint8)
            else:
                f_a = np.ascontiguousarray(np.asarray(flags, dtype=np.uint8))
                if f_a.ndim != 2:
                    raise ValueError(f"{fn}() argument 'flags' must be 2-D, not {f_a.ndim}-D")
            self._handle.evaluate_arrays(float(thickness_mm), float(width_mm), 1, s_a, x_a,
                                         z_a, 0 if flags is None else 1, f_a)
        return self.results()

    def results(self) -> List[RuleResult]:
        """The results of the last evaluation, in rule order."""
        return _results(self._handle, self._rules)

    @property
    def rules(self) -> Tuple[ToleranceRule, ...]:
        """The rules this verdict judges by, in order."""
        return tuple(self._rules)

    @property
    def failed(self) -> int:
        """The number of rules that failed in the last evaluation."""
        return int(_capi.flt_verdict_failed(self._handle))

    def __repr__(self) -> str:
        return f"<flatline.Verdict: {len(self._rules)} rules>"
