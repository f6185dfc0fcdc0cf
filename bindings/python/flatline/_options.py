# SPDX-License-Identifier: Apache-2.0
"""Keyword options: the C option names (flatline/common.h), mapped generically.

Nothing here lists the options: the table comes from the library itself
(flt_option_at / flt_option_info / flt_option_choice_at), so an option added
to the C library is a keyword argument in Python as soon as the library is
rebuilt.

Values are numbers; an option whose value is a choice also takes the name
of a choice (``robust="huber"``, ``flat_reference="mean"``,
``source_encoder_mode="chunk"``). An on/off option (``rigid_motion``) takes
True or False, and so does a choice whose first value is "none":
``robust=True`` is the first mode after "none", the recommended one (Huber).
"""

from __future__ import annotations

import math
import numbers
from functools import lru_cache
from typing import AbstractSet, Any, Dict, Iterable, Mapping, NamedTuple, Optional, Tuple

from . import capi as _capi
from ._errors import InvalidArgumentError, NotFoundError

#: A keyword value: a number, a choice's name, or True/False for an on/off
#: option (and for a choice whose first value is "none").
OptionValue = Any


class OptionInfo(NamedTuple):
    """One option key as the library describes it."""

    name: str  #: the keyword, e.g. "knot_spacing"
    key: int  #: the C key (FLT_OPT_*)
    min_value: float  #: inclusive lower bound
    max_value: float  #: inclusive upper bound
    default: float  #: the C default
    is_integer: bool  #: True if only whole numbers are accepted
    #: for an option whose value is a choice, the value of each name
    #: (e.g. {"none": 0, "huber": 1, "tukey": 2}); empty for a number
    choices: Mapping[str, int] = {}

    @property
    def is_switch(self) -> bool:
        """True for an on/off option (0 or 1, no names): it takes a bool."""
        return (self.is_integer and not self.choices and self.min_value == 0.0
                and self.max_value == 1.0)


def _choices(key: int, is_integer: bool) -> Dict[str, int]:
    table: Dict[str, int] = {}
    index = 0
    while is_integer:
        try:
            name, value = _capi.flt_option_choice_at(key, index)
        except NotFoundError:  # past the last choice, or a number
            break
        table[name] = int(value)
        index += 1
    return table


@lru_cache(maxsize=None)
def _info(key: int) -> OptionInfo:
    name, lo, hi, default, is_int = _capi.flt_option_info(key)
    return OptionInfo(name, int(key), lo, hi, default, bool(is_int),
                      _choices(key, bool(is_int)))


def option_info(name: str) -> OptionInfo:
    """Describes the option ``name``; raises NotFoundError (a KeyError) if the
    library has no option of that name."""
    if not isinstance(name, str):
        raise TypeError(f"option name must be a str, not {type(name).__name__}")
    return _info(int(_capi.flt_option_find(name)))


def options() -> Dict[str, OptionInfo]:
    """Every option of the library, by name, in key order."""
    table: Dict[str, OptionInfo] = {}
    index = 0
    while True:
        try:
            key = _capi.flt_option_at(index)
        except NotFoundError:  # past the last key
            break
        info = _info(int(key))
        table[info.name] = info
        index += 1
    return table


def _option_value(function: str, info: OptionInfo, value: OptionValue) -> float:
    """A keyword value as the double the C bag stores."""
    name = info.name
    if isinstance(value, str):
        if not info.choices:
            raise TypeError(f"{function}() option '{name}' must be a real number, not str")
        try:
            return float(info.choices[value])
        except KeyError:
            raise ValueError(
                f"{function}() option '{name}' = {value!r} is not one of "
                f"{', '.join(repr(c) for c in info.choices)}"
            ) from None
    if isinstance(value, bool):
        # True as a length is a mistake worth reporting; as a switch, or as
        # a choice that can be off ("none"), it says what it means.
        if info.is_switch:
            return 1.0 if value else 0.0
        if info.choices and info.choices.get("none") == 0:
            return 1.0 if value else 0.0
        raise TypeError(
            f"{function}() option '{name}' must be a "
            + (f"real number or one of {', '.join(repr(c) for c in info.choices)}"
               if info.choices else "real number")
            + ", not bool"
        )
    if not isinstance(value, numbers.Real):
        raise TypeError(
            f"{function}() option '{name}' must be a real number"
            + (f" or one of {', '.join(repr(c) for c in info.choices)}" if info.choices else "")
            + f", not {type(value).__name__}"
        )
    try:
        return float(value)
    except OverflowError:  # an int like 10**400: out of range, as the C bag says
        info = option_info(name)
        text = str(value)
        if len(text) > 60:
            text = text[:60] + "..."
        raise InvalidArgumentError(
            f"{function}: option '{name}' = {text} is outside "
            f"[{info.min_value:g}, {info.max_value:g}]"
        ) from None


def make_options(function: str, kwargs: Mapping[str, OptionValue],
                 prefixes: Optional[Tuple[str, ...]] = None,
                 names: Optional[AbstractSet[str]] = None
                 ) -> Optional[_capi.flt_options]:
    """A C option bag holding `kwargs` (None when there are none, which the
    library reads as "every default"). An unknown name raises TypeError, as
    Python does for any unexpected keyword argument; so does an option of
    another component, one whose name starts with none of `prefixes` or is
    not in `names` (the C component would refuse it). A value out of bounds
    raises InvalidArgumentError (a ValueError) with the library's message; a
    name that is not one of an option's choices, ValueError."""
    if not kwargs:
        return None
    bag = _capi.flt_options_create()
    for name, value in kwargs.items():
        try:
            key = _capi.flt_option_find(name)
        except NotFoundError as e:
            # the library's closest name, when it has one (a typo)
            hint = str(e).partition("; did you mean ")[2]
            hint = f"; did you mean {hint}" if hint else ";"
            raise TypeError(
                f"{function}() got an unexpected keyword argument '{name}' "
                f"(libflatline has no option of that name{hint} flatline.options() "
                f"lists them)"
            ) from None
        if prefixes is not None and not name.startswith(prefixes):
            raise TypeError(
                f"{function}() got an unexpected keyword argument '{name}' "
                f"(an option of another component; {function}() reads "
                f"{', '.join(p + '*' for p in prefixes)})"
            )
        if names is not None and name not in names:
            raise TypeError(
                f"{function}() got an unexpected keyword argument '{name}' "
                f"(an option of another component; {function}() reads "
                f"{', '.join(sorted(names))})"
            )
        _capi.flt_options_set(bag, key, _option_value(function, _info(int(key)), value))
    return bag


def prefixed_options(*prefixes: str) -> Dict[str, OptionInfo]:
    """The options whose names start with one of `prefixes`, in key order."""
    return {name: info for name, info in options().items()
            if name.startswith(prefixes)}


def options_doc(names: Iterable[str]) -> str:
    """Docstring lines describing the options `names` (in library order)."""
    wanted = set(names)
    lines = []
    for info in options().values():
        if info.name not in wanted:
            continue
        if info.choices:
            by_value = {v: n for n, v in info.choices.items()}
            lines.append(
                f"        {info.name} (str or int): one of "
                f"{', '.join(repr(n) for n in info.choices)}; default "
                f"{by_value.get(int(info.default), info.default)!r}"
            )
            continue
        if info.is_switch:
            lines.append(f"        {info.name} (bool): default {bool(info.default)}")
            continue
        kind = "int" if info.is_integer else "float"
        hi = "inf" if math.isinf(info.max_value) else f"{info.max_value:g}"
        lines.append(
            f"        {info.name} ({kind}): default {info.default:g}, "
            f"range [{info.min_value:g}, {hi}]"
        )
    return "\n".join(lines)
